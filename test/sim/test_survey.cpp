// The reference survey (sim/survey.h), the flight seed and the world
// deformation: survey points lie on the analytic surfaces within the range
// noise, one point per voxel, the crop holds, a second flight seed changes the
// flight but not the world, and the deformation moves the surface by the
// configured amount at its centre and not at all outside its extent.
#include <cmath>
#include <string>
#include <unordered_set>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/map/voxel_key.h"
#include "rvlio/sim/presets.h"
#include "rvlio/sim/simulator.h"
#include "rvlio/sim/survey.h"

namespace rvlio::sim {
namespace {

// A coarse, cheap survey of x in [x_min, x_max].
SimOptions CheapSurvey(const std::string& preset, double x_min, double x_max) {
  SimOptions o = *PresetOptions(preset);
  o.duration = 1.0;
  o.lidar.columns = 64;
  o.lidar.beams = 8;
  o.survey.enabled = true;
  o.survey.angular_step = 1.0;
  o.survey.voxel_size = 0.1;
  o.survey.station_spacing = 4.0;
  o.survey.x_min = x_min;
  o.survey.x_max = x_max;
  return o;
}

std::unique_ptr<Simulator> Make(const SimOptions& o) {
  StatusOr<std::unique_ptr<Simulator>> sim = Simulator::Create(o);
  EXPECT_TRUE(sim.ok()) << sim.status().message();
  return sim.ok() ? std::move(*sim) : nullptr;
}

SurveyResult Survey(const Simulator& sim) {
  StatusOr<SurveyResult> r = sim.Survey();
  EXPECT_TRUE(r.ok()) << r.status().message();
  return r.ok() ? *r : SurveyResult();
}

TEST(Survey, PointsLieOnTheWorldSurfacesWithinTheRangeNoise) {
  for (const std::string& preset : PresetNames()) {
    // Noise-free on every preset (points on the surfaces to float rounding),
    // with the default noise on the tunnel.
    const std::vector<double> noises =
        preset == "tunnel" ? std::vector<double>{0.0, 0.002} : std::vector<double>{0.0};
    for (const double noise : noises) {
      SimOptions o = CheapSurvey(preset, -3.0, 9.0);
      o.survey.range_noise = noise;
      const auto sim = Make(o);
      ASSERT_NE(sim, nullptr);
      const SurveyResult r = Survey(*sim);
      EXPECT_EQ(r.stations.size(), 3u) << preset;
      EXPECT_GT(r.p_world.size(), 10000u) << preset;
      EXPECT_GT(r.returns, static_cast<int64_t>(r.p_world.size())) << preset;
      // |range noise| bounds the distance to the surface hit (less at
      // oblique incidence); 6 sigma, plus float rounding of the coordinates.
      const double bound = 6.0 * noise + 2e-5;
      double worst = 0.0;
      for (const Eigen::Vector3d& p : r.p_world)
        worst = std::max(worst, sim->world().DistanceToSurface(p));
      EXPECT_LT(worst, bound) << preset << " noise " << noise;
      for (const Eigen::Vector3d& s : r.stations) {
        EXPECT_FALSE(sim->world().InsideFeature(s)) << preset;
        EXPECT_GE(sim->world().DistanceToSurface(s), kStationClearance) << preset;
      }
    }
  }
}

TEST(Survey, OnePointPerVoxelAndWallsAreCovered) {
  SimOptions o = CheapSurvey("featureless", 0.0, 12.0);
  o.survey.angular_step = 0.5;
  o.survey.station_spacing = 2.0;
  const auto sim = Make(o);
  ASSERT_NE(sim, nullptr);
  const SurveyResult r = Survey(*sim);
  const double inv = 1.0 / o.survey.voxel_size;
  std::unordered_set<VoxelKey, VoxelKeyHash> keys;
  for (const Eigen::Vector3d& p : r.p_world)
    EXPECT_TRUE(keys.insert(KeyOf(p, inv)).second) << "two points in the voxel of " << p.transpose();
  // The flat left wall (y = y_center + width / 2) between x = 2 and 10, 0.5 m
  // from floor and ceiling: nearly every 0.1 m voxel holds a point.
  const WorldLayout& L = sim->layout();
  const double y_wall = L.y_center + L.half_width;
  std::unordered_set<VoxelKey, VoxelKeyHash> wall;
  for (const Eigen::Vector3d& p : r.p_world)
    if (std::abs(p.y() - y_wall) < 0.01 && p.x() >= 2.0 && p.x() < 10.0 &&
        p.z() >= L.z_floor + 0.5 && p.z() < L.z_ceiling - 0.5)
      wall.insert(KeyOf(Eigen::Vector3d(p.x(), 0.0, p.z()), inv));
  const double cells = 8.0 * inv * (L.z_ceiling - L.z_floor - 1.0) * inv;
  EXPECT_GT(wall.size(), 0.95 * cells);
  EXPECT_LE(wall.size(), cells + 2 * (8.0 + L.z_ceiling - L.z_floor) * inv);
}

TEST(Survey, CropKeepsStationsAndPointsInTheRange) {
  const auto sim = Make(CheapSurvey("tunnel", 10.0, 22.0));
  ASSERT_NE(sim, nullptr);
  const SurveyResult r = Survey(*sim);
  ASSERT_FALSE(r.p_world.empty());
  double x_lo = 1e9, x_hi = -1e9;
  for (const Eigen::Vector3d& p : r.p_world) {
    x_lo = std::min(x_lo, p.x());
    x_hi = std::max(x_hi, p.x());
  }
  EXPECT_GE(x_lo, 10.0);
  EXPECT_LE(x_hi, 22.0);
  EXPECT_LT(x_lo, 10.2);  // the range is covered to its ends
  EXPECT_GT(x_hi, 21.8);
  for (const Eigen::Vector3d& s : r.stations) {
    EXPECT_GT(s.x(), 10.0);
    EXPECT_LT(s.x(), 22.0);
  }
  // Outside the world: InvalidInput naming the keys; x_max <= x_min: Validate.
  const auto outside = Make(CheapSurvey("tunnel", 200.0, 300.0));
  ASSERT_NE(outside, nullptr);
  StatusOr<SurveyResult> bad = outside->Survey();
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(bad.status().message().find("survey.x_min"), std::string::npos);
  SimOptions reversed = CheapSurvey("tunnel", 5.0, 1.0);
  const Status s = reversed.Validate();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("survey.x_max"), std::string::npos);
}

TEST(FlightSeed, ChangesTheFlightButNotTheWorld) {
  const SimOptions a = CheapSurvey("tunnel", -2.0, 6.0);
  SimOptions b = a, same = a, other_world = a;
  b.flight_seed = 7;
  same.flight_seed = a.seed;  // explicit = default
  other_world.seed = 2;
  const auto sa = Make(a), sb = Make(b), ss = Make(same), sw = Make(other_world);
  ASSERT_TRUE(sa && sb && ss && sw);
  // The flight: same path, other yaw motion; other noise.
  const TimeNs t = sa->start_time_ns() + SecondsToNs(0.9);
  EXPECT_LT((sa->TruthAt(t).T_world_imu.t - sb->TruthAt(t).T_world_imu.t).norm(), 1e-12);
  const Trajectory ga = sa->GroundTruth(100.0), gb = sb->GroundTruth(100.0),
                   gs = ss->GroundTruth(100.0);
  ASSERT_EQ(ga.size(), gb.size());
  double yaw_diff = 0.0;
  for (size_t i = 0; i < ga.size(); ++i) {
    EXPECT_EQ(ga[i].q_world_imu.coeffs(), gs[i].q_world_imu.coeffs());
    yaw_diff = std::max(yaw_diff, ga[i].q_world_imu.angularDistance(gb[i].q_world_imu));
  }
  const Scan scan_a = sa->SimulateScan(3), scan_b = sb->SimulateScan(3), scan_s = ss->SimulateScan(3);
  int differ = 0;
  for (size_t i = 0; i < scan_a.points.size(); ++i) {
    differ += scan_a.points[i].p_lidar != scan_b.points[i].p_lidar;
    EXPECT_EQ(scan_a.points[i].p_lidar, scan_s.points[i].p_lidar);
  }
  EXPECT_GT(differ, static_cast<int>(scan_a.points.size()) / 2);
  // The world: identical surfaces and features, the same reference map.
  ASSERT_EQ(sa->world().faces().size(), sb->world().faces().size());
  for (size_t i = 0; i < sa->world().faces().size(); ++i)
    EXPECT_EQ(sa->world().faces()[i].relief.waves().front().phase,
              sb->world().faces()[i].relief.waves().front().phase);
  ASSERT_EQ(sa->world().boxes().size(), sb->world().boxes().size());
  for (size_t i = 0; i < sa->world().boxes().size(); ++i)
    EXPECT_EQ(sa->world().boxes()[i].center, sb->world().boxes()[i].center);
  const SurveyResult ra = Survey(*sa), rb = Survey(*sb), rw = Survey(*sw);
  EXPECT_EQ(ra.p_world, rb.p_world);
  EXPECT_NE(ra.p_world, rw.p_world);  // another world seed: another world
}

// Range to the surface along a ray from `origin` in direction `dir`.
double RangeTo(const World& world, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) {
  RayHit hit;
  EXPECT_TRUE(world.Raycast(origin, dir, 100.0, &hit));
  return hit.range;
}

// Rough walls, no features (nothing in front of the walls).
SimOptions Bare() {
  SimOptions o = *PresetOptions("tunnel");
  o.world.clutter_count = 0;
  o.world.sparse_spacing = 0.0;
  o.duration = 1.0;
  return o;
}

// The shell's surfaces as world.deformation and world.band name them.
struct ShellSurface {
  const char* surface;
  Eigen::Vector3d dir;  // from the centre line towards the surface
  float reflectivity;   // its own (world_builder.cpp)
};
const ShellSurface kShell[] = {{"left", Eigen::Vector3d::UnitY(), 80.0f},
                               {"right", -Eigen::Vector3d::UnitY(), 80.0f},
                               {"ceiling", Eigen::Vector3d::UnitZ(), 60.0f},
                               {"floor", -Eigen::Vector3d::UnitZ(), 40.0f}};

TEST(Deformation, MovesTheSurfaceByTheAmplitudeAtItsCentreAndNotOutside) {
  for (const ShellSurface& c : kShell) {
    for (const double amplitude : {0.05, -0.03}) {
      SimOptions o = Bare();
      o.world.deformation.surface = c.surface;
      o.world.deformation.amplitude = amplitude;
      o.world.deformation.x_center = 40.0;
      o.world.deformation.length = 10.0;
      SimOptions flat = o;
      flat.world.deformation.amplitude = 0.0;
      const auto deformed = Make(o), plain = Make(flat);
      ASSERT_TRUE(deformed && plain);
      const WorldLayout& L = plain->layout();
      const double z_mid = 0.5 * (L.z_floor + L.z_ceiling);
      // Rays along the surface normal keep (u, v): the range shrinks by the
      // displacement towards the inside, exactly.
      auto moved = [&](double x, double across) {
        const Eigen::Vector3d origin =
            c.dir.z() != 0.0 ? Eigen::Vector3d(x, L.y_center + across, z_mid)
                             : Eigen::Vector3d(x, L.y_center, L.z_floor + across);
        return RangeTo(plain->world(), origin, c.dir) - RangeTo(deformed->world(), origin, c.dir);
      };
      const std::string what = std::string(c.surface) + " " + std::to_string(amplitude);
      for (double across : {0.7, 2.0, 4.5}) {
        EXPECT_NEAR(moved(40.0, across), amplitude, 1e-7) << what;
        EXPECT_NEAR(moved(42.5, across), 0.5 * amplitude, 1e-7) << what;  // quarter length
        EXPECT_NEAR(moved(37.5, across), 0.5 * amplitude, 1e-7) << what;
        // Outside the extent only the root finder's tolerance (1e-9 m) differs.
        for (double x : {30.0, 35.0, 45.0, 46.0, 60.0, 5.0})
          EXPECT_NEAR(moved(x, across), 0.0, 1e-8) << what;
      }
    }
  }
}

// world.band: a ray that hits the painted surface within [x_min, x_max]
// returns the band's reflectivity, elsewhere the surface's own; the other
// surfaces and the geometry are as without it.
TEST(Band, PaintsItsSurfaceBetweenItsXAndNothingElse) {
  for (const ShellSurface& c : kShell) {
    SimOptions o = Bare();
    o.world.band.surface = c.surface;
    o.world.band.x_min = 16.0;
    o.world.band.x_max = 19.0;
    o.world.band.reflectivity = 250.0;
    SimOptions plain_options = o;
    plain_options.world.band.reflectivity = 0.0;
    const auto painted = Make(o), plain = Make(plain_options);
    ASSERT_TRUE(painted && plain);
    const WorldLayout& L = plain->layout();
    const Eigen::Vector3d centre(0.0, L.y_center, 0.5 * (L.z_floor + L.z_ceiling));
    for (double x : {15.9, 16.1, 17.5, 18.9, 19.1, 40.0}) {
      for (const ShellSurface& target : kShell) {
        RayHit a, b;
        const Eigen::Vector3d origin = centre + Eigen::Vector3d(x, 0.0, 0.0);
        ASSERT_TRUE(painted->world().Raycast(origin, target.dir, 100.0, &a));
        ASSERT_TRUE(plain->world().Raycast(origin, target.dir, 100.0, &b));
        EXPECT_EQ(a.range, b.range) << c.surface << " x " << x;  // paint, not geometry
        EXPECT_EQ(b.reflectivity, target.reflectivity);
        const bool on_band = &target == &c && x > 16.0 && x < 19.0;
        EXPECT_EQ(a.reflectivity, on_band ? 250.0f : target.reflectivity)
            << c.surface << " band, ray to " << target.surface << " at x " << x;
      }
    }
  }
}

TEST(Deformation, ABulgeIsLimitedAcrossTheWall) {
  SimOptions o = Bare();
  o.world.deformation.surface = "left";
  o.world.deformation.amplitude = 0.08;
  o.world.deformation.x_center = 40.0;
  o.world.deformation.length = 6.0;
  o.world.deformation.across_center = 3.0;  // m above the floor
  o.world.deformation.across_length = 2.0;
  SimOptions flat = o;
  flat.world.deformation.amplitude = 0.0;
  const auto deformed = Make(o), plain = Make(flat);
  ASSERT_TRUE(deformed && plain);
  const WorldLayout& L = plain->layout();
  auto moved = [&](double x, double height) {
    const Eigen::Vector3d origin(x, L.y_center, L.z_floor + height);
    return RangeTo(plain->world(), origin, Eigen::Vector3d::UnitY()) -
           RangeTo(deformed->world(), origin, Eigen::Vector3d::UnitY());
  };
  EXPECT_NEAR(moved(40.0, 3.0), 0.08, 1e-7);
  EXPECT_NEAR(moved(40.0, 3.5), 0.04, 1e-7);
  EXPECT_NEAR(moved(41.5, 3.5), 0.02, 1e-7);
  EXPECT_NEAR(moved(40.0, 4.0), 0.0, 1e-8);
  EXPECT_NEAR(moved(40.0, 1.5), 0.0, 1e-8);
  EXPECT_NEAR(moved(43.0, 3.0), 0.0, 1e-8);
}

TEST(Deformation, TheSurveyIgnoresItUnlessAskedAndTheFlightSeesIt) {
  SimOptions o = CheapSurvey("featureless", 4.0, 16.0);
  o.world.deformation.surface = "left";
  o.world.deformation.amplitude = 0.05;
  o.world.deformation.x_center = 10.0;
  o.world.deformation.length = 4.0;
  SimOptions plain = o, surveyed = o;
  plain.world.deformation.amplitude = 0.0;
  surveyed.survey.deformed = true;
  o.survey.range_noise = plain.survey.range_noise = surveyed.survey.range_noise = 0.0;
  const auto s_default = Make(o), s_plain = Make(plain), s_deformed = Make(surveyed);
  ASSERT_TRUE(s_default && s_plain && s_deformed);
  EXPECT_EQ(Survey(*s_default).p_world, Survey(*s_plain).p_world);
  // The deformed survey: the wall at x = 10 stands 5 cm inside, far from it
  // where it was.
  const WorldLayout& L = s_plain->layout();
  const double y_wall = L.y_center + L.half_width;
  int near_centre = 0, far = 0;
  for (const Eigen::Vector3d& p : Survey(*s_deformed).p_world) {
    if (std::abs(p.y() - y_wall) > 0.2 || p.z() < L.z_floor + 0.3 || p.z() > L.z_ceiling - 0.3)
      continue;  // not on the wall
    if (std::abs(p.x() - 10.0) < 0.1) {
      EXPECT_NEAR(p.y(), y_wall - 0.05, 0.002);
      ++near_centre;
    } else if (std::abs(p.x() - 10.0) > 2.0) {
      EXPECT_NEAR(p.y(), y_wall, 1e-5);
      ++far;
    }
  }
  EXPECT_GT(near_centre, 50);
  EXPECT_GT(far, 500);
  // The flight flies in the deformed world (the ray casts above show what
  // that does to the wall).
  EXPECT_EQ(s_default->world().faces()[3].relief.bumps().size(), 1u);
  EXPECT_EQ(s_plain->world().faces()[3].relief.bumps().size(), 0u);
}

}  // namespace
}  // namespace rvlio::sim

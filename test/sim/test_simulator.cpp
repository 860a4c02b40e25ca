// The simulator as a whole: presets, option validation, determinism, the
// time order of the emitted data, ground truth, and the world's layout
// (features where the issue says they are).
#include <cmath>

#include <gtest/gtest.h>

#include "rvlio/sim/presets.h"
#include "rvlio/sim/random.h"
#include "rvlio/sim/simulator.h"

namespace rvlio::sim {
namespace {

// A cheap configuration for tests that run whole sequences.
SimOptions Small(const char* preset, double duration) {
  SimOptions o = *PresetOptions(preset);
  o.duration = duration;
  o.lidar.columns = 64;
  o.lidar.beams = 8;
  return o;
}

TEST(Presets, AllValidateAndUnknownNamesListThem) {
  for (const std::string& name : PresetNames()) {
    StatusOr<SimOptions> o = PresetOptions(name);
    ASSERT_TRUE(o.ok()) << name;
    SimOptions copy = *o;
    EXPECT_TRUE(copy.Validate().ok()) << name << ": " << copy.Validate().message();
    auto sim = Simulator::Create(*o);
    ASSERT_TRUE(sim.ok()) << name;
    // The motion (plus a little hover, or the rest of a last landing) fits
    // the preset's duration.
    EXPECT_LT((*sim)->trajectory().MotionEnd(), o->duration) << name;
    EXPECT_GT((*sim)->trajectory().MotionEnd(),
              o->duration - 5.0 - o->trajectory.landing_time) << name;
  }
  StatusOr<SimOptions> bad = PresetOptions("tunel");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidInput);
  for (const std::string& name : PresetNames())
    EXPECT_NE(bad.status().message().find(name), std::string::npos);
}

TEST(Options, CrossFieldRulesNameTheKey) {
  struct Case {
    void (*edit)(SimOptions&);
    const char* key;
  };
  const Case cases[] = {
      {[](SimOptions& o) { o.trajectory.waypoints = "1,0,0; 2,0,0"; }, "trajectory.waypoints"},
      {[](SimOptions& o) { o.trajectory.waypoints = "0,0,0; 0,20,1"; }, "trajectory.waypoints"},
      {[](SimOptions& o) { o.trajectory.waypoints = "0,0,0; 0,0,9"; }, "trajectory.waypoints"},
      {[](SimOptions& o) {  // out of a closed entrance (an open one may be left)
         o.world.open_entrance = false;
         o.trajectory.waypoints = "0,0,0; -6,0,1";
       },
       "trajectory.waypoints"},
      {[](SimOptions& o) { o.lidar.vfov_min = 30.0; }, "lidar.vfov_max"},
      {[](SimOptions& o) { o.lidar.min_range = 200.0; }, "lidar.max_range"},
      {[](SimOptions& o) { o.lidar.beams = 0; }, "lidar.beams"},
      {[](SimOptions& o) { o.imu.rate = -1.0; }, "imu.rate"},
      {[](SimOptions& o) { o.world.layout = "cave"; }, "world.layout"},
      {[](SimOptions& o) { o.world.roughness_wavelength_max = 0.5; },
       "world.roughness_wavelength_max"},
      {[](SimOptions& o) {
         o.extrinsics.imu_T_lidar.rotation_xyzw = {0, 0, 0, 0.5};
       },
       "extrinsics"},
      {[](SimOptions& o) { o.duration = 0.05; }, "duration"},
  };
  for (const Case& c : cases) {
    SimOptions o = *PresetOptions("tunnel");
    c.edit(o);
    const Status s = o.Validate();
    ASSERT_FALSE(s.ok()) << c.key;
    EXPECT_NE(s.message().find(c.key), std::string::npos) << s.message();
    EXPECT_FALSE(Simulator::Create(o).ok());
  }
}

TEST(Determinism, SameSeedSameDataDifferentSeedDifferentNoise) {
  SimOptions o = *PresetOptions("tunnel");
  o.duration = 0.35;
  auto collect = [](const SimOptions& opts, std::vector<ImuSample>* imu, std::vector<Scan>* scans) {
    auto sim = Simulator::Create(opts);
    ASSERT_TRUE(sim.ok());
    (*sim)->Run(
        [&](const ImuSample& m) {
          imu->push_back(m);
          return true;
        },
        [&](const Scan& s, int, int) {
          scans->push_back(s);
          return true;
        });
  };
  std::vector<ImuSample> i1, i2, i3;
  std::vector<Scan> s1, s2, s3;
  collect(o, &i1, &s1);
  collect(o, &i2, &s2);
  o.seed = 2;
  collect(o, &i3, &s3);
  ASSERT_EQ(s1.size(), 3u);
  ASSERT_EQ(i1.size(), i2.size());
  for (size_t k = 0; k < i1.size(); ++k) {
    EXPECT_EQ(i1[k].t_ns, i2[k].t_ns);
    EXPECT_EQ(i1[k].acc_imu, i2[k].acc_imu);
    EXPECT_EQ(i1[k].gyro_imu, i2[k].gyro_imu);
  }
  bool imu_differs = false, scan_differs = false;
  for (size_t k = 0; k < i1.size(); ++k) imu_differs |= i1[k].acc_imu != i3[k].acc_imu;
  for (size_t k = 0; k < s1.size(); ++k) {
    ASSERT_EQ(s1[k].points.size(), s2[k].points.size());
    for (size_t j = 0; j < s1[k].points.size(); ++j) {
      ASSERT_EQ(s1[k].points[j].p_lidar, s2[k].points[j].p_lidar);
      ASSERT_EQ(s1[k].points[j].t_ns, s2[k].points[j].t_ns);
      ASSERT_EQ(s1[k].points[j].intensity, s2[k].points[j].intensity);
      scan_differs |= s1[k].points[j].p_lidar != s3[k].points[j].p_lidar;
    }
  }
  EXPECT_TRUE(imu_differs);
  EXPECT_TRUE(scan_differs);
  // Run's k-th scan is SimulateScan(k).
  auto sim = Simulator::Create(*PresetOptions("tunnel"));
  const Scan again = (*sim)->SimulateScan(2);
  for (size_t j = 0; j < again.points.size(); ++j)
    ASSERT_EQ(again.points[j].p_lidar, s1[2].points[j].p_lidar);
}

// IMU samples on their grid, scans on the 10 Hz grid, each scan after all
// IMU samples up to its end and before any later one; counts as announced.
TEST(Run, EmitsInTimeOrderOnFixedGrids) {
  const SimOptions o = Small("tunnel", 3.0);
  auto sim = Simulator::Create(o);
  ASSERT_TRUE(sim.ok());
  const TimeNs t0 = (*sim)->start_time_ns();
  EXPECT_EQ(t0, SecondsToNs(o.start_time));
  int64_t imu_count = 0, scan_count = 0;
  TimeNs last_imu = -1;
  const bool done = (*sim)->Run(
      [&](const ImuSample& m) {
        EXPECT_EQ(m.t_ns, t0 + imu_count * 5000000);  // 200 Hz
        if (scan_count > 0) {
          EXPECT_GT(m.t_ns, (*sim)->ScanStartTime(scan_count - 1) + 100000000);
        }
        last_imu = m.t_ns;
        ++imu_count;
        return true;
      },
      [&](const Scan& s, int rows, int cols) {
        EXPECT_EQ(rows, 8);
        EXPECT_EQ(cols, 64);
        EXPECT_EQ(s.t_start_ns, t0 + scan_count * 100000000);
        EXPECT_EQ(s.t_end_ns, s.t_start_ns + 63LL * 100000000 / 64);
        EXPECT_GE(last_imu, s.t_start_ns + 100000000);  // IMU up to the scan end came first
        ++scan_count;
        return true;
      });
  EXPECT_TRUE(done);
  EXPECT_EQ(scan_count, 30);
  EXPECT_EQ(scan_count, (*sim)->scan_count());
  EXPECT_EQ(imu_count, 601);
  EXPECT_EQ(imu_count, (*sim)->imu_count());
  // A callback returning false stops the run.
  int scans = 0;
  EXPECT_FALSE((*sim)->Run([](const ImuSample&) { return true; },
                           [&](const Scan&, int, int) { return ++scans < 2; }));
  EXPECT_EQ(scans, 2);
}

TEST(Run, GroundTruthSamplesTheTrueTrajectory) {
  auto sim = Simulator::Create(*PresetOptions("tunnel"));
  ASSERT_TRUE(sim.ok());
  const Trajectory gt = (*sim)->GroundTruth(100.0);
  EXPECT_EQ(gt.size(), static_cast<size_t>((*sim)->options().duration * 100.0) + 1);
  EXPECT_EQ(gt.front().t_ns, (*sim)->start_time_ns());
  for (size_t i = 0; i < gt.size(); i += 97) {
    const TruthState s = (*sim)->TruthAt(gt[i].t_ns);
    EXPECT_EQ(gt[i].t_ns, gt.front().t_ns + static_cast<TimeNs>(i) * 10000000);
    EXPECT_LT((gt[i].p_world_imu - s.T_world_imu.t).norm(), 1e-12);
    EXPECT_LT(gt[i].q_world_imu.angularDistance(s.T_world_imu.quaternion()), 1e-9);
  }
  EXPECT_LT((gt.back().p_world_imu - Eigen::Vector3d(50, 0, 4.5)).norm(), 1e-9);
}

// Tunnel: many features in the entrance region, sparse ones after it (about
// one per sparse_spacing), none in the flight corridor; the world frame puts
// the start pose a few metres inside the entrance, on the floor.
TEST(WorldLayout, TunnelHasRichEntranceAndSparseFeaturesAfter) {
  const SimOptions o = *PresetOptions("tunnel");
  auto sim = Simulator::Create(o);
  ASSERT_TRUE(sim.ok());
  const WorldLayout& L = (*sim)->layout();
  EXPECT_NEAR(L.x_entrance, -o.world.start_depth, 1e-12);
  EXPECT_NEAR(L.x_end - L.x_entrance, 100.5, 1e-12);
  EXPECT_NEAR(2 * L.half_width, 10.45, 1e-12);
  EXPECT_NEAR(L.z_ceiling - L.z_floor, 7.8, 1e-12);
  EXPECT_LT(L.z_floor, 0.0);
  int entrance = 0, sparse = 0;
  std::vector<double> sparse_x;
  for (const Eigen::AlignedBox3d& b : (*sim)->world().FeatureBounds()) {
    const double x = b.center().x();
    EXPECT_GE(x, L.x_entrance);
    EXPECT_LE(x, L.x_end);
    if (x <= L.clutter_end) {
      ++entrance;
    } else {
      ++sparse;
      sparse_x.push_back(x);
    }
  }
  EXPECT_GE(entrance, o.world.clutter_count);  // stacks count twice
  const double sparse_length = L.x_end - L.clutter_end;
  EXPECT_LE(sparse, static_cast<int>(sparse_length / o.world.sparse_spacing) + 1);
  EXPECT_GE(sparse, static_cast<int>(sparse_length / o.world.sparse_spacing) - 1);
  std::sort(sparse_x.begin(), sparse_x.end());
  for (size_t i = 1; i < sparse_x.size(); ++i)
    EXPECT_GT(sparse_x[i] - sparse_x[i - 1], 0.5 * o.world.sparse_spacing);
  // The entrance region is dense: features per metre an order above the rest.
  EXPECT_GT(entrance / o.world.clutter_length, 10.0 * sparse / sparse_length);
}

TEST(WorldLayout, FeaturesKeepClearOfTheFlightPath) {
  for (const std::string& name : PresetNames()) {
    const SimOptions o = *PresetOptions(name);
    auto sim = Simulator::Create(o);
    ASSERT_TRUE(sim.ok());
    const std::vector<Eigen::Vector3d> path = (*sim)->trajectory().SamplePath(0.05);
    for (const Eigen::AlignedBox3d& b : (*sim)->world().FeatureBounds())
      for (const Eigen::Vector3d& p : path)
        ASSERT_GE(b.exteriorDistance(p), o.world.path_clearance - 1e-9) << name;
    // The whole flight stays inside the shell, or out in the open beyond an
    // open portal (the portals preset starts and ends outside).
    const auto& L = (*sim)->layout();
    const bool open_entrance = o.world.layout == "tunnel" && o.world.open_entrance;
    for (double tau = 0.0; tau < o.duration; tau += 0.1) {
      const Eigen::Vector3d p =
          (*sim)->TruthAt((*sim)->start_time_ns() + SecondsToNs(tau)).T_world_imu.t;
      if ((open_entrance && p.x() < L.x_entrance) || (!o.world.end_wall && p.x() > L.x_end))
        continue;
      EXPECT_TRUE(L.Inside(p, 0.0)) << name << " t=" << tau;
    }
  }
}

TEST(WorldLayout, FeaturelessHasNoFeaturesAndNoVisibleEnds) {
  const SimOptions o = *PresetOptions("featureless");
  auto sim = Simulator::Create(o);
  ASSERT_TRUE(sim.ok());
  EXPECT_TRUE((*sim)->world().boxes().empty());
  EXPECT_TRUE((*sim)->world().cylinders().empty());
  const WorldLayout& L = (*sim)->layout();
  for (const Eigen::Vector3d& w : (*sim)->trajectory().waypoints()) {
    EXPECT_GT(w.x() - L.x_entrance, o.lidar.max_range);
    EXPECT_GT(L.x_end - w.x(), o.lidar.max_range);
  }
  // Every return comes from the four walls: no point has an axial neighbour
  // structure, i.e. all lie on the planes |y - yc| = w/2 or z = floor/ceiling.
  const Scan s = (*sim)->SimulateScan(200);
  for (const LidarPoint& p : s.points) {
    if (p.p_lidar.isZero()) continue;
    const Eigen::Vector3d q =
        ((*sim)->TruthAt(p.t_ns).T_world_imu * (*sim)->T_imu_lidar()) * p.p_lidar.cast<double>();
    const double d = std::min({std::abs(std::abs(q.y() - L.y_center) - L.half_width),
                               std::abs(q.z() - L.z_floor), std::abs(q.z() - L.z_ceiling)});
    ASSERT_LT(d, 0.2);  // within the range noise of a wall
  }
}

TEST(WorldLayout, HallHasPillarsStairsAndDoorways) {
  const SimOptions o = *PresetOptions("hall");
  auto sim = Simulator::Create(o);
  ASSERT_TRUE(sim.ok());
  const World& w = (*sim)->world();
  int pillars = 0, holes = 0, stair_steps = 0;
  for (const Cylinder& c : w.cylinders())
    if (std::abs(c.axis.z()) > 0.99 && 2 * c.half_length > o.world.height) ++pillars;
  for (const Face& f : w.faces()) holes += static_cast<int>(f.holes.size());
  for (const Box& b : w.boxes())
    if (std::abs(b.half.y() - 0.75) < 1e-12 && std::abs(b.half.x() - 0.15) < 1e-12) ++stair_steps;
  EXPECT_GE(pillars, 8);
  EXPECT_EQ(holes, o.world.openings);
  EXPECT_EQ(stair_steps, 10);
  EXPECT_GE(w.boxes().size(), static_cast<size_t>(o.world.clutter_count / 2));
}



// The weak-feature surfaces are rough by a few centimetres, tilting local
// normals by a few degrees (paper Fig. 1b), and the roughness is seeded.
TEST(WorldLayout, TunnelSurfacesAreRoughByAFewCentimetresAndDegrees) {
  const SimOptions o = *PresetOptions("tunnel");
  auto sim = Simulator::Create(o);
  ASSERT_TRUE(sim.ok());
  Rng rng(4);
  double max_h = 0.0, max_tilt = 0.0, sum_tilt2 = 0.0;
  int n = 0;
  for (const Face& f : (*sim)->world().faces()) {
    ASSERT_FALSE(f.relief.flat());
    for (int i = 0; i < 2000; ++i) {
      double hu = 0, hv = 0;
      const double h = f.relief.Height(rng.Uniform(-50, 50), rng.Uniform(-50, 50), &hu, &hv);
      const double tilt = std::atan(std::hypot(hu, hv));
      max_h = std::max(max_h, std::abs(h));
      max_tilt = std::max(max_tilt, tilt);
      sum_tilt2 += tilt * tilt;
      ++n;
    }
  }
  const double rms_tilt_deg = std::sqrt(sum_tilt2 / n) * 180 / M_PI;
  EXPECT_LE(max_h, o.world.roughness_amplitude + 1e-12);
  EXPECT_GT(max_h, 0.4 * o.world.roughness_amplitude);
  EXPECT_GT(rms_tilt_deg, 1.0);
  EXPECT_LT(rms_tilt_deg, 5.0);
  EXPECT_LT(max_tilt * 180 / M_PI, 10.0);
  std::printf("surface roughness: max %.3f m, normal tilt rms %.2f deg, max %.2f deg\n", max_h,
              rms_tilt_deg, max_tilt * 180 / M_PI);
  // Another seed gives other surfaces.
  SimOptions other = o;
  other.seed = 99;
  auto sim2 = Simulator::Create(other);
  ASSERT_TRUE(sim2.ok());
  EXPECT_NE((*sim)->world().faces()[0].relief.Height(1.0, 2.0),
            (*sim2)->world().faces()[0].relief.Height(1.0, 2.0));
}

}  // namespace
}  // namespace rvlio::sim

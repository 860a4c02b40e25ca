// Map metrics (eval/map_metrics.h) on constructed clouds with known answers.
#include "rvlio/eval/map_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace rvlio {
namespace {

// Random points on z = offset over [-2, 2]^2 with Gaussian noise along z,
// keeping those that `keep` accepts.
template <class Keep>
std::vector<Eigen::Vector3d> Plane(int n, double offset_m, double noise_m, unsigned seed, Keep keep) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  std::normal_distribution<double> noise(0.0, noise_m);
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d x(u(rng), u(rng), offset_m + (noise_m > 0 ? noise(rng) : 0.0));
    if (keep(x)) p.push_back(x);
  }
  return p;
}
std::vector<Eigen::Vector3d> Plane(int n, double offset_m, double noise_m, unsigned seed) {
  return Plane(n, offset_m, noise_m, seed, [](const Eigen::Vector3d&) { return true; });
}

TEST(MapMetrics, NoisyPlaneOffsetByTwoCentimetres) {
  const std::vector<Eigen::Vector3d> ref = Plane(200000, 0.0, 0.0005, 1);
  const std::vector<Eigen::Vector3d> map = Plane(40000, 0.02, 0.002, 2);
  StatusOr<MapEvalResult> r = EvaluateMap(map, ref, MapEvalOptions());
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_NEAR(r->accuracy.mean, 0.02, 0.0005);
  EXPECT_NEAR(r->accuracy.median, 0.02, 0.0005);
  EXPECT_NEAR(r->accuracy.rmse, std::sqrt(0.02 * 0.02 + 0.002 * 0.002), 0.0005);
  EXPECT_GT(r->accuracy.p95, r->accuracy.median);
  EXPECT_LT(r->accuracy.max, 0.04);
  // The nearest reference point is never closer than the plane.
  EXPECT_GE(r->nearest.mean, r->accuracy.mean - 1e-4);
  EXPECT_EQ(r->outlier_fraction, 0.0);
  EXPECT_GT(r->completeness, 0.999);
  EXPECT_EQ(r->map_points, map.size());
  EXPECT_EQ(r->ref_points, ref.size());
  // Chamfer: both directions are about the 2 cm offset (plus spacing).
  EXPECT_GT(r->chamfer_m, 0.02);
  EXPECT_LT(r->chamfer_m, 0.03);
}

TEST(MapMetrics, HalfAPlaneIsHalfComplete) {
  const std::vector<Eigen::Vector3d> ref = Plane(100000, 0.0, 0.0, 3);
  std::vector<Eigen::Vector3d> map;
  for (const Eigen::Vector3d& p : ref)
    if (p.x() < 0.0) map.push_back(p);
  MapEvalOptions options;
  options.max_distance = 0.01;
  StatusOr<MapEvalResult> r = EvaluateMap(map, ref, options);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_NEAR(r->completeness, 0.5, 0.01);
  EXPECT_LT(r->accuracy.max, 1e-6);  // the map lies on the reference
  EXPECT_EQ(r->outlier_fraction, 0.0);
}

TEST(MapMetrics, AHoleInTheReferenceMakesOutliersNotErrors) {
  const double hole_m = 1.0;
  const std::vector<Eigen::Vector3d> ref = Plane(
      200000, 0.0, 0.0, 4, [&](const Eigen::Vector3d& p) { return p.head<2>().norm() > hole_m; });
  const std::vector<Eigen::Vector3d> map = Plane(40000, 0.0, 0.001, 5);
  MapEvalOptions options;
  StatusOr<MapEvalResult> r = EvaluateMap(map, ref, options);
  ASSERT_TRUE(r.ok()) << r.status().message();
  // Map points farther than D inside the hole's rim have no reference.
  const double r_in = hole_m - options.max_distance;
  EXPECT_NEAR(r->outlier_fraction, M_PI * r_in * r_in / 16.0, 0.01);
  EXPECT_GT(r->completeness, 0.999);
  EXPECT_LT(r->accuracy.rmse, 0.0015);  // the rest lies on the plane (1 mm noise)
  // Inliers near the rim, whose k neighbours are not all within the search
  // radius or lie on one side, are counted, not measured.
  EXPECT_EQ(r->inliers, r->accuracy.count + r->no_plane);
}

TEST(MapMetrics, ProfileFindsTheDisplacedSection) {
  // Two walls y = +-2 along x in [0, 20]; the map's walls converge by 5 cm
  // each over x in [12, 13).
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> along(0.0, 20.0), up(0.0, 3.0);
  std::vector<Eigen::Vector3d> ref, map;
  for (int i = 0; i < 200000; ++i) {
    const double side = (i % 2 == 0) ? 2.0 : -2.0;
    ref.emplace_back(along(rng), side, up(rng));
  }
  for (int i = 0; i < 40000; ++i) {
    const double x = along(rng), side = (i % 2 == 0) ? 2.0 : -2.0;
    const double bulge = (x >= 12.0 && x < 13.0) ? -0.05 * side / 2.0 : 0.0;
    map.emplace_back(x, side + bulge, up(rng));
  }
  StatusOr<MapEvalResult> r = EvaluateMap(map, ref, MapEvalOptions());
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_NEAR(std::abs(r->axis_direction.x()), 1.0, 1e-3);
  ASSERT_GE(r->profile.size(), 20u);
  for (const MapProfileBin& b : r->profile) {
    if (b.map_with_plane == 0) continue;
    const double mid = b.chainage_m + 0.5;
    const bool displaced = std::abs(mid - 12.5) < 0.5;
    if (displaced) {
      EXPECT_NEAR(b.median_m, 0.05, 0.003) << b.chainage_m;
    } else if (std::abs(mid - 12.5) > 1.5) {
      EXPECT_LT(b.p95_m, 1e-5) << b.chainage_m;
    }
    EXPECT_GT(b.completeness, 0.98) << b.chainage_m;
  }
}

TEST(MapMetrics, ResultsDoNotDependOnTheThreadCount) {
  const std::vector<Eigen::Vector3d> ref = Plane(50000, 0.0, 0.001, 7);
  const std::vector<Eigen::Vector3d> map = Plane(20000, 0.01, 0.003, 8);
  MapEvalOptions one, two;
  two.threads = 2;
  StatusOr<MapEvalResult> a = EvaluateMap(map, ref, one), b = EvaluateMap(map, ref, two);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->accuracy.rmse, b->accuracy.rmse);
  EXPECT_EQ(a->accuracy.p95, b->accuracy.p95);
  EXPECT_EQ(a->completeness, b->completeness);
  EXPECT_EQ(a->chamfer_m, b->chamfer_m);
}

// Completeness and the Chamfer distance against brute force over every pair,
// on clouds scattered in a volume (about 60 % covered) and in no spatial
// order, with duplicates: the voxel-ordered searches change nothing.
TEST(MapMetrics, CompletenessAndChamferEqualBruteForce) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 2.0);
  std::vector<Eigen::Vector3d> ref, map;
  for (int i = 0; i < 3000; ++i) ref.emplace_back(u(rng), u(rng), u(rng));
  for (int i = 0; i < 2000; ++i) map.emplace_back(u(rng) + 0.5, u(rng), u(rng));
  ref.push_back(ref[5]);
  map.push_back(map[7]);
  const auto stored = [](const Eigen::Vector3d& p) { return p.cast<float>().cast<double>(); };
  const auto nearest = [&](const Eigen::Vector3d& q, const std::vector<Eigen::Vector3d>& cloud) {
    double best = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& p : cloud) best = std::min(best, (stored(p) - q).norm());
    return best;
  };
  MapEvalOptions o;
  o.max_distance = 0.1;
  const double D = o.max_distance;
  size_t covered = 0, inliers = 0;
  double chamfer_ref = 0.0, chamfer_map = 0.0;
  for (const Eigen::Vector3d& r : ref) {
    const double d = nearest(r, map);
    covered += d <= D ? 1 : 0;
    chamfer_ref += std::min(d, D);
  }
  for (const Eigen::Vector3d& m : map) {
    const double d = nearest(m, ref);
    inliers += d <= D ? 1 : 0;
    chamfer_map += std::min(d, D);
  }
  const StatusOr<MapEvalResult> r = EvaluateMap(map, ref, o);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_GT(covered, ref.size() / 3);
  EXPECT_LT(covered, ref.size());
  EXPECT_EQ(r->completeness, static_cast<double>(covered) / ref.size());
  EXPECT_EQ(r->inliers, inliers);
  EXPECT_NEAR(r->chamfer_m, 0.5 * (chamfer_map / map.size() + chamfer_ref / ref.size()), 1e-12);
}

TEST(MapMetrics, RefusesEmptyNonFiniteAndDisjointClouds) {
  const std::vector<Eigen::Vector3d> ref = Plane(1000, 0.0, 0.0, 9);
  std::vector<Eigen::Vector3d> far = ref;
  for (Eigen::Vector3d& p : far) p.x() += 1000.0;  // another frame
  std::vector<Eigen::Vector3d> nan = ref;
  nan[3].z() = std::numeric_limits<double>::quiet_NaN();
  const MapEvalOptions o;
  EXPECT_NE(EvaluateMap({}, ref, o).status().message().find("the map has no points"),
            std::string::npos);
  EXPECT_NE(EvaluateMap(ref, {}, o).status().message().find("the reference has no points"),
            std::string::npos);
  EXPECT_NE(EvaluateMap(nan, ref, o).status().message().find("1 of 1000 points"), std::string::npos);
  const StatusOr<MapEvalResult> disjoint = EvaluateMap(far, ref, o);
  ASSERT_FALSE(disjoint.ok());
  EXPECT_EQ(disjoint.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(disjoint.status().message().find("do not overlap"), std::string::npos);
}

// The same two clouds shifted far from the origin (106 km: beyond the
// reference structure's key reach at 0.1 m voxels; a UTM easting and
// northing: beyond float32's millimetres) give the same figures: both are
// evaluated in the reference's local frame; the axis comes back shifted.
TEST(MapMetrics, CloudsFarFromTheOriginGiveTheSameFigures) {
  const std::vector<Eigen::Vector3d> ref = Plane(40000, 0.0, 0.0005, 11);
  const std::vector<Eigen::Vector3d> map = Plane(10000, 0.01, 0.002, 12);
  const MapEvalOptions o;
  const StatusOr<MapEvalResult> near = EvaluateMap(map, ref, o);
  ASSERT_TRUE(near.ok()) << near.status().message();
  for (const Eigen::Vector3d& shift :
       {Eigen::Vector3d(106000.0, 0.0, 0.0), Eigen::Vector3d(500000.0, 5400000.0, 312.0)}) {
    std::vector<Eigen::Vector3d> map_far = map, ref_far = ref;
    for (Eigen::Vector3d& p : map_far) p += shift;
    for (Eigen::Vector3d& p : ref_far) p += shift;
    const StatusOr<MapEvalResult> far = EvaluateMap(map_far, ref_far, o);
    ASSERT_TRUE(far.ok()) << far.status().message();
    EXPECT_EQ(far->inliers, near->inliers);
    EXPECT_NEAR(far->accuracy.rmse, near->accuracy.rmse, 1e-6);
    EXPECT_NEAR(far->completeness, near->completeness, 1e-4);
    EXPECT_NEAR(far->chamfer_m, near->chamfer_m, 1e-6);
    EXPECT_NEAR((far->axis_origin - shift - near->axis_origin).norm(), 0.0, 1e-6);
    // The moving overload gives the same.
    const StatusOr<MapEvalResult> moved = EvaluateMap(std::move(map_far), std::move(ref_far), o);
    ASSERT_TRUE(moved.ok());
    EXPECT_EQ(moved->chamfer_m, far->chamfer_m);
  }
  // A reference point beyond the reach from the others is refused, not dropped.
  std::vector<Eigen::Vector3d> stray = ref;
  stray.push_back(Eigen::Vector3d(250000.0, 0.0, 0.0));
  const StatusOr<MapEvalResult> refused = EvaluateMap(map, stray, o);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("the reference: 1 of 40001 points"), std::string::npos)
      << refused.status().message();
}

TEST(MapMetrics, PrincipalAxisStartsAtTheSmallestProjection) {
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i <= 100; ++i) p.emplace_back(-5.0 + 0.1 * i, 0.01 * (i % 3), 0.0);
  const ChainageAxis axis = PrincipalAxis(p);
  EXPECT_NEAR(axis.direction.x(), 1.0, 1e-6);
  EXPECT_NEAR(axis.Chainage(p.front()), 0.0, 1e-9);
  EXPECT_NEAR(axis.Chainage(p.back()), 10.0, 1e-6);
}

// A profile step far below the reference's extent would allocate bins by the
// billion: refused before any search, one line naming the bound and the
// smallest step it allows; a step at the bound works.
TEST(MapMetrics, ProfileStepGivingTooManyBinsIsRefused) {
  std::vector<Eigen::Vector3d> ref;
  for (int i = 0; i <= 1000; ++i) ref.emplace_back(0.01 * i, 0.01 * (i % 7), 0.0);  // 10 m
  MapEvalOptions o;
  o.profile_step = 1e-5;  // 10^6 bins
  const StatusOr<MapEvalResult> refused = EvaluateMap(ref, ref, o);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(refused.status().message().find("profile step 1e-05 m gives 1e+06 bins"),
            std::string::npos) << refused.status().message();
  EXPECT_NE(refused.status().message().find("at most 100000"), std::string::npos);
  o.profile_step = 1e-300;  // the bin count does not even fit an integer
  EXPECT_FALSE(EvaluateMap(ref, ref, o).ok());
  const double extent_m = PrincipalAxis(ref).Chainage(ref.back());
  o.profile_step = extent_m / static_cast<double>(kMaxProfileBins - 1);
  const StatusOr<MapEvalResult> at_bound = EvaluateMap(ref, ref, o);
  ASSERT_TRUE(at_bound.ok()) << at_bound.status().message();
  EXPECT_LE(at_bound->profile.size(), kMaxProfileBins);
}

// A max distance beyond kMaxDistanceVoxels search voxels is refused (its
// cost would grow with its cube for every point without a neighbour).
TEST(MapMetrics, MaxDistanceBeyondTheSearchBoundIsRefused) {
  const std::vector<Eigen::Vector3d> ref = Plane(2000, 0.0, 0.0, 1);
  MapEvalOptions o;
  o.max_distance = 1000.0;
  const StatusOr<MapEvalResult> refused = EvaluateMap(ref, ref, o);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(refused.status().message().find("max distance 1000 m is more than 10 search voxels"),
            std::string::npos) << refused.status().message();
  o.max_distance = kMaxDistanceVoxels * o.search.voxel_size;  // at the bound
  EXPECT_TRUE(EvaluateMap(ref, ref, o).ok());
  o.search.voxel_size = 1.0;  // coarser voxels allow a larger D
  o.max_distance = 5.0;
  EXPECT_TRUE(EvaluateMap(ref, ref, o).ok());
}

TEST(MapMetrics, ProgressReachesOneFromTheCallingThread) {
  const std::vector<Eigen::Vector3d> ref = Plane(20000, 0.0, 0.0, 1);
  const std::vector<Eigen::Vector3d> map = Plane(10000, 0.01, 0.0, 2);
  MapEvalOptions o;
  o.threads = 2;
  std::vector<double> seen;
  const std::thread::id caller = std::this_thread::get_id();
  const StatusOr<MapEvalResult> r = EvaluateMap(map, ref, o, [&](double fraction) {
    EXPECT_EQ(std::this_thread::get_id(), caller);
    seen.push_back(fraction);
  });
  ASSERT_TRUE(r.ok()) << r.status().message();
  ASSERT_FALSE(seen.empty());
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  EXPECT_EQ(seen.back(), 1.0);
}

}  // namespace
}  // namespace rvlio

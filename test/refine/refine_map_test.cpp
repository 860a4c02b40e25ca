// The leave-one-out map of batch refinement: exact k-NN over the points a
// scan may see, never the scan's own points, backups standing in for
// shadowed points, and association that cannot anchor a scan on itself.
#include <algorithm>
#include <random>
#include <set>
#include <tuple>

#include <gtest/gtest.h>

#include "rvlio/refine/map.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;
using FloatKey = std::tuple<float, float, float>;

FloatKey KeyOfPoint(const Vector3d& p) {
  return {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())};
}

MapOptions Options() {
  MapOptions o;
  o.voxel_size = 1.0;
  o.max_points_per_voxel = 20;
  o.min_point_distance = 0.1;
  return o;
}

// Random points in a 6 m cube; every scan's points are distinct, and a third
// of each scan's points lie within 5 cm of an earlier scan's point (shadowed
// at insertion: these exercise the backups).
std::vector<std::vector<Vector3d>> RandomScans(std::mt19937& rng, int scans, int points) {
  std::uniform_real_distribution<double> u(-3.0, 3.0), jitter(-0.028, 0.028);
  std::vector<std::vector<Vector3d>> out(scans);
  for (int s = 0; s < scans; ++s)
    for (int i = 0; i < points; ++i) {
      if (s > 0 && i % 3 == 0) {
        const auto& prev = out[rng() % s];
        out[s].push_back(prev[rng() % prev.size()] + Vector3d(jitter(rng), jitter(rng), jitter(rng)));
      } else {
        out[s].emplace_back(u(rng), u(rng), u(rng));
      }
    }
  return out;
}

TEST(RefineMap, KNearestIsExactAndNeverReturnsTheExcludedScansPoints) {
  std::mt19937 rng(7);
  const auto scans = RandomScans(rng, 6, 3000);
  RefineMap map(Options());
  std::vector<std::set<FloatKey>> own(scans.size());
  for (size_t s = 0; s < scans.size(); ++s) {
    map.Insert(static_cast<int32_t>(s), scans[s]);
    for (const auto& p : scans[s]) own[s].insert(KeyOfPoint(p));
  }
  ASSERT_GT(map.stats().backups, 100);  // the shadowing case really occurs
  std::uniform_real_distribution<double> u(-3.5, 3.5);
  ScanNeighbors nb;
  std::vector<Vector3d> visible;
  std::vector<int32_t> ids;
  int checked = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const int32_t exclude = static_cast<int32_t>(rng() % (scans.size() + 1)) - 1;  // -1: none
    const Vector3d q(u(rng), u(rng), u(rng));
    const int k = 1 + static_cast<int>(rng() % 8);
    const double max_dist = trial % 2 ? 0.6 : 2.5;
    const int n = map.KNearest(q, k, max_dist, exclude, &nb);
    // Brute force over the points visible to `exclude`.
    map.VisiblePoints(exclude, &visible, &ids);
    std::vector<double> d2;
    for (const auto& p : visible) {
      const double d = (p - q).squaredNorm();
      if (d <= max_dist * max_dist) d2.push_back(d);
    }
    std::sort(d2.begin(), d2.end());
    ASSERT_EQ(n, std::min<int>(k, static_cast<int>(d2.size()))) << "trial " << trial;
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(nb.dist2[i], d2[i], 1e-5) << "trial " << trial << " rank " << i;
      EXPECT_NE(nb.scan_ids[i], exclude);
      if (exclude >= 0) {  // not one of the excluded scan's points
        EXPECT_EQ(own[exclude].count(KeyOfPoint(nb.points[i])), 0u) << "trial " << trial;
        ++checked;
      }
    }
    for (int32_t id : ids) ASSERT_NE(id, exclude);
  }
  EXPECT_GT(checked, 1000);
}

// Two scans see the same wall patch 2 cm apart: scan 1's points are shadowed
// by scan 0's at insertion and stored as backups. Each scan sees the other's
// points at full density; a region only scan 0 saw is empty for scan 0.
TEST(RefineMap, BackupsStandInForShadowedPointsAndOwnOnlyRegionsAreEmpty) {
  std::vector<Vector3d> a, b, only_a;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) {
      a.emplace_back(0.2 * i + 0.05, 0.2 * j + 0.05, 0.5);
      b.emplace_back(0.2 * i + 0.05, 0.2 * j + 0.05, 0.52);
      only_a.emplace_back(10.0 + 0.2 * i, 0.2 * j + 0.05, 0.5);
    }
  MapOptions mo = Options();
  mo.max_points_per_voxel = 100;
  RefineMap map(mo);
  map.Insert(0, a);
  map.Insert(0, only_a);
  map.Insert(1, b);
  EXPECT_EQ(map.stats().entries, 50);
  EXPECT_EQ(map.stats().backups, 25);
  ScanNeighbors nb;
  const Vector3d q(0.45, 0.45, 0.5);
  ASSERT_EQ(map.KNearest(q, 5, 1.0, 0, &nb), 5);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(nb.scan_ids[i], 1);
    EXPECT_NEAR(nb.points[i].z(), 0.52, 1e-6);
  }
  ASSERT_EQ(map.KNearest(q, 5, 1.0, 1, &nb), 5);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(nb.scan_ids[i], 0);
  ASSERT_EQ(map.KNearest(q, 5, 1.0, RefineMap::kNoScan, &nb), 5);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(nb.scan_ids[i], 0);  // primaries
  EXPECT_EQ(map.KNearest(Vector3d(10.4, 0.45, 0.5), 5, 1.0, 0, &nb), 0);
  EXPECT_EQ(map.KNearest(Vector3d(10.4, 0.45, 0.5), 5, 1.0, 1, &nb), 5);
  map.Clear();
  EXPECT_EQ(map.KNearest(q, 5, 1.0, 1, &nb), 0);
  EXPECT_EQ(map.stats().entries, 0);
}

// The association itself: scan 0 lies on the plane z = 0, scan 1 on the
// plane z = 0.05 over the same area. Scan 0 associated on its own behalf
// must fit planes through scan 1's points (residual -5 cm, normal towards the
// sensor above), never through its own (residual 0), which is what a map
// with its own points gives (the control).
TEST(RefineMap, AssociationNeverAnchorsAScanOnItsOwnPoints) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  std::vector<Vector3d> plane0, plane1;
  for (int i = 0; i < 4000; ++i) {
    plane0.emplace_back(u(rng), u(rng), 0.0);
    plane1.emplace_back(u(rng), u(rng), 0.05);
  }
  MapOptions mo = Options();
  mo.min_point_distance = 0.02;
  mo.max_points_per_voxel = 400;  // both planes stored in full
  RefineMap map(mo);
  map.Insert(0, plane0);
  map.Insert(1, plane1);
  const Pose3 T_world_lidar(Eigen::Matrix3d::Identity(), Vector3d(0.0, 0.0, 2.0));
  std::vector<Vector3d> scan0_lidar;
  for (int i = 0; i < 500; ++i) scan0_lidar.push_back(T_world_lidar.Inverse() * plane0[i]);
  ConstraintOptions co;
  ConstraintList list;
  AssociationStats stats;
  AssociateScan(scan0_lidar, T_world_lidar, 0, map, co, &list, &stats);
  ASSERT_GT(list.size(), 400u);
  EXPECT_EQ(stats.num_accepted, static_cast<int>(list.size()));
  for (const Constraint& c : list) {
    ASSERT_NEAR(c.residual, -0.05, 2e-3);
    EXPECT_NEAR(c.normal_world.z(), 1.0, 1e-3);
  }
  // Control: with nothing excluded each point's nearest neighbour is itself
  // and the planes it fits are pulled towards its own (|mean r| < 5 cm).
  ScanNeighbors nb;
  for (int i = 0; i < 50; ++i) {
    ASSERT_EQ(map.KNearest(plane0[i], 5, 1.0, RefineMap::kNoScan, &nb), 5);
    EXPECT_EQ(nb.dist2[0], 0.0);
    EXPECT_EQ(nb.scan_ids[0], 0);
  }
  AssociateScan(scan0_lidar, T_world_lidar, RefineMap::kNoScan, map, co, &list, &stats);
  ASSERT_GT(list.size(), 50u);  // mixed neighbourhoods often fail the flatness test
  double sum = 0.0;
  for (const Constraint& c : list) sum += c.residual;
  EXPECT_GT(sum / static_cast<double>(list.size()), -0.04);
}

}  // namespace
}  // namespace rvlio

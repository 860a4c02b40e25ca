#include "rvlio/map/voxel_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/map/voxel_order.h"

namespace rvlio {
namespace {

std::vector<Eigen::Vector3d> RandomCloud(std::mt19937* rng, int n, double half_extent) {
  std::uniform_real_distribution<double> u(-half_extent, half_extent);
  std::vector<Eigen::Vector3d> pts(n);
  for (auto& p : pts) p = Eigen::Vector3d(u(*rng), u(*rng), u(*rng));
  return pts;
}

// Squared distances of the k nearest points within max_dist, by brute force.
std::vector<double> BruteForce(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& q,
                               int k, double max_dist) {
  std::vector<double> d2;
  for (const auto& p : pts) {
    const double d = (p - q).squaredNorm();
    if (d <= max_dist * max_dist) d2.push_back(d);
  }
  std::sort(d2.begin(), d2.end());
  if (static_cast<int>(d2.size()) > k) d2.resize(k);
  return d2;
}

bool NearBoundary(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& q,
                  double max_dist) {
  for (const auto& p : pts)
    if (std::abs((p - q).norm() - max_dist) < 1e-4) return true;
  return false;
}

TEST(VoxelMap, KNearestMatchesBruteForce) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int checked = 0, partial = 0, empty = 0;
  for (int trial = 0; trial < 200; ++trial) {
    MapOptions options;
    options.voxel_size = 0.2 + 1.8 * unit(rng);
    options.max_points_per_voxel = 1 + static_cast<int>(40 * unit(rng));
    options.min_point_distance = (trial % 3 == 0) ? 0.0 : 0.05 * unit(rng);
    VoxelMap map(options);
    const double half_extent = 1.0 + 9.0 * unit(rng);
    const int n = static_cast<int>(3000 * unit(rng));
    map.Insert(RandomCloud(&rng, n, half_extent));
    // The reference is what the map actually stored (capacity and spacing drop points).
    const std::vector<Eigen::Vector3d> stored = map.Points();
    ASSERT_EQ(stored.size(), map.Size());

    for (int query = 0; query < 20; ++query) {
      const double reach = (query % 4 == 0) ? 3.0 * half_extent : 1.2 * half_extent;
      std::uniform_real_distribution<double> uq(-reach, reach);
      const Eigen::Vector3d q(uq(rng), uq(rng), uq(rng));
      const int k = (query % 5 == 0) ? kMaxNeighbors : 1 + static_cast<int>(10 * unit(rng));
      const double max_dist = (query % 7 == 0) ? 100.0 : 0.05 + 4.0 * unit(rng);
      if (NearBoundary(stored, q, max_dist)) continue;  // float storage vs the exact bound
      NeighborBuffer nb;
      const int found = map.KNearest(q, k, max_dist, &nb);
      const std::vector<double> expected = BruteForce(stored, q, k, max_dist);
      ASSERT_EQ(found, static_cast<int>(expected.size()))
          << "trial " << trial << " query " << query;
      ASSERT_EQ(nb.size, found);
      for (int i = 0; i < found; ++i) {
        EXPECT_NEAR(nb.dist2[i], expected[i], 1e-9 + 1e-6 * expected[i]) << "rank " << i;
        EXPECT_NEAR((nb.points[i] - q).squaredNorm(), nb.dist2[i], 1e-9);
        if (i > 0) {
          EXPECT_LE(nb.dist2[i - 1], nb.dist2[i]);
        }
      }
      ++checked;
      if (found > 0 && found < k) ++partial;
      if (found == 0) ++empty;
    }
  }
  // The random setup must exercise full, partial and empty answers.
  EXPECT_GT(checked, 3500);
  EXPECT_GT(partial, 100);
  EXPECT_GT(empty, 100);
}

// Brute force restricted to the points of the 27 voxels around q's voxel
// (what the nearby search sees).
std::vector<double> BruteForceNearby(const std::vector<Eigen::Vector3d>& pts,
                                     const Eigen::Vector3d& q, int k, double max_dist,
                                     double voxel) {
  std::vector<Eigen::Vector3d> near;
  const Eigen::Vector3d home = (q / voxel).array().floor();
  for (const auto& p : pts) {
    const Eigen::Vector3d key = (p / voxel).array().floor();
    if ((key - home).cwiseAbs().maxCoeff() <= 1.0) near.push_back(p);
  }
  return BruteForce(near, q, k, max_dist);
}

// The nearby search gives the k nearest among the 27 voxels around the
// query's, exactly; it misses farther points by design.
TEST(VoxelMap, NearbySearchIsExactWithinTheTwentySevenVoxels) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int checked = 0, missed_farther = 0;
  for (int trial = 0; trial < 60; ++trial) {
    MapOptions options;
    options.voxel_size = 0.2 + 0.8 * unit(rng);
    options.neighbor_search = "nearby";
    VoxelMap map(options);
    MapOptions exact_options = options;
    exact_options.neighbor_search = "exact";
    VoxelMap exact(exact_options);
    const std::vector<Eigen::Vector3d> cloud = RandomCloud(&rng, 300 + trial * 20, 4.0);
    map.Insert(cloud);
    exact.Insert(cloud);
    const std::vector<Eigen::Vector3d> stored = map.Points();
    for (int query = 0; query < 30; ++query) {
      std::uniform_real_distribution<double> uq(-4.5, 4.5);
      const Eigen::Vector3d q(uq(rng), uq(rng), uq(rng));
      const int k = 1 + static_cast<int>(8 * unit(rng));
      const double max_dist = 3.0;
      if (NearBoundary(stored, q, max_dist)) continue;
      NeighborBuffer nb, nb_exact;
      const int found = map.KNearest(q, k, max_dist, &nb);
      const std::vector<double> expected =
          BruteForceNearby(stored, q, k, max_dist, options.voxel_size);
      ASSERT_EQ(found, static_cast<int>(expected.size())) << trial << " " << query;
      for (int i = 0; i < found; ++i) EXPECT_NEAR(nb.dist2[i], expected[i], 1e-6);
      exact.KNearest(q, k, max_dist, &nb_exact);
      if (nb_exact.size > found || (found > 0 && nb_exact.dist2[found - 1] < nb.dist2[found - 1]))
        ++missed_farther;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1500);
  EXPECT_GT(missed_farther, 10);  // the setup reaches beyond the 27 voxels
}

// Small voxels, many of them: the shell-by-shell search (not the scan over
// all voxels) has to go beyond the precomputed shells.
TEST(VoxelMap, DeepShellSearchMatchesBruteForce) {
  std::mt19937 rng(5);
  MapOptions options;
  options.voxel_size = 0.25;
  options.min_point_distance = 0.0;
  VoxelMap map(options);
  map.Insert(RandomCloud(&rng, 30000, 10.0));
  const std::vector<Eigen::Vector3d> stored = map.Points();
  std::uniform_real_distribution<double> uq(-10.0, 10.0);
  for (int query = 0; query < 200; ++query) {
    const Eigen::Vector3d q(uq(rng), uq(rng), uq(rng));
    const int k = 10 + query % 20;
    const double max_dist = 1.6;
    if (NearBoundary(stored, q, max_dist)) continue;
    NeighborBuffer nb;
    const std::vector<double> expected = BruteForce(stored, q, k, max_dist);
    ASSERT_EQ(map.KNearest(q, k, max_dist, &nb), static_cast<int>(expected.size()));
    for (int i = 0; i < nb.size; ++i) EXPECT_NEAR(nb.dist2[i], expected[i], 1e-6 * expected[i]);
  }
}

TEST(VoxelMap, EmptyMapAndBadQueries) {
  VoxelMap map;
  NeighborBuffer nb;
  EXPECT_EQ(map.KNearest(Eigen::Vector3d::Zero(), 5, 1.0, &nb), 0);
  map.Insert({Eigen::Vector3d(0.1, 0.2, 0.3)});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(map.KNearest(Eigen::Vector3d(nan, 0, 0), 5, 1.0, &nb), 0);
  EXPECT_EQ(map.KNearest(Eigen::Vector3d::Zero(), 5, 0.0, &nb), 0);
  EXPECT_EQ(map.KNearest(Eigen::Vector3d::Zero(), 5, 1.0, &nb), 1);
  EXPECT_NEAR(nb.points[0].y(), 0.2, 1e-6);
}

TEST(VoxelMap, InsertRespectsCapacityAndSpacing) {
  MapOptions options;
  options.voxel_size = 1.0;
  options.max_points_per_voxel = 4;
  options.min_point_distance = 0.1;
  VoxelMap map(options);
  EXPECT_TRUE(map.InsertPoint(Eigen::Vector3d(0.5, 0.5, 0.5)));
  EXPECT_FALSE(map.InsertPoint(Eigen::Vector3d(0.55, 0.5, 0.5)));  // 5 cm from a stored point
  EXPECT_TRUE(map.InsertPoint(Eigen::Vector3d(0.65, 0.5, 0.5)));
  EXPECT_TRUE(map.InsertPoint(Eigen::Vector3d(0.8, 0.5, 0.5)));
  EXPECT_TRUE(map.InsertPoint(Eigen::Vector3d(0.95, 0.5, 0.5)));
  EXPECT_FALSE(map.InsertPoint(Eigen::Vector3d(0.1, 0.1, 0.1)));  // voxel full
  // Spacing applies within a voxel only: 2 cm away but across the boundary.
  EXPECT_TRUE(map.InsertPoint(Eigen::Vector3d(1.01, 0.5, 0.5)));
  EXPECT_FALSE(map.InsertPoint(Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0, 0)));
  EXPECT_EQ(map.Size(), 5u);
  EXPECT_EQ(map.NumVoxels(), 2u);
}

TEST(VoxelMap, GrowthKeepsEveryPoint) {
  MapOptions options;
  options.voxel_size = 0.5;
  options.min_point_distance = 0.0;
  options.max_points_per_voxel = 1000;
  VoxelMap map(options);
  std::mt19937 rng(7);
  // 20k points on a 200 m line: thousands of voxels, several table growths.
  std::vector<Eigen::Vector3d> pts;
  std::uniform_real_distribution<double> u(-100.0, 100.0), v(-0.3, 0.3);
  for (int i = 0; i < 20000; ++i) pts.emplace_back(u(rng), v(rng), v(rng));
  map.Insert(pts);
  EXPECT_EQ(map.Size(), pts.size());
  NeighborBuffer nb;
  for (int i = 0; i < 2000; i += 7) {
    ASSERT_EQ(map.KNearest(pts[i], 1, 0.5, &nb), 1);
    EXPECT_LT(nb.dist2[0], 1e-10);
  }
}

TEST(VoxelMap, RemoveFarKeepsTheWindow) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    MapOptions options;
    options.voxel_size = 0.3 + unit(rng);
    options.min_point_distance = 0.0;
    options.max_points_per_voxel = 1000;
    VoxelMap map(options);
    const std::vector<Eigen::Vector3d> pts = RandomCloud(&rng, 5000, 20.0);
    map.Insert(pts);
    ASSERT_EQ(map.Size(), pts.size());
    const Eigen::Vector3d center = 10.0 * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    const double radius = 5.0 + 10.0 * unit(rng);
    map.RemoveFar(center, radius);

    // A point's voxel centre is within half a voxel diagonal of the point.
    const double half_diag = 0.5 * std::sqrt(3.0) * options.voxel_size;
    size_t must_keep = 0, may_keep = 0;
    for (const auto& p : pts) {
      const double d = (p - center).norm();
      if (d < radius - half_diag) ++must_keep;
      if (d <= radius + half_diag) ++may_keep;
    }
    EXPECT_GE(map.Size(), must_keep);
    EXPECT_LE(map.Size(), may_keep);
    map.ForEachPoint([&](const Eigen::Vector3d& p) {
      EXPECT_LE((p - center).norm(), radius + half_diag + 1e-6);
    });
    // Queries still work after the rebuild and see only the kept points.
    NeighborBuffer nb;
    for (const auto& p : pts) {
      const double d = (p - center).norm();
      if (d < radius - half_diag) {
        ASSERT_EQ(map.KNearest(p, 1, 0.01, &nb), 1);
        EXPECT_LT(nb.dist2[0], 1e-10);
      } else if (d > radius + half_diag) {
        EXPECT_EQ(map.KNearest(p, 1, 1e-3, &nb), 0);
      }
    }
    // Freed blocks are reused: re-inserting everything adds every point again.
    const size_t kept = map.Size();
    map.Insert(pts);
    EXPECT_EQ(map.Size(), kept + pts.size());
  }
}

// A point beyond the packed keys' reach (~10^6 voxels along an axis: 104.8 km
// at 0.1 m) is not stored, and says so: counted, and CheckReach refuses the
// cloud with the counts, the reach and the cloud's span.
TEST(VoxelMap, PointsBeyondTheReachAreCountedAndReported) {
  MapOptions o;
  o.voxel_size = 0.1;
  o.min_point_distance = 0.0;
  const double reach_m = VoxelMapReach(o.voxel_size);
  EXPECT_NEAR(reach_m, 104755.2, 1e-6);  // (2^20 - 1024) voxels
  EXPECT_NEAR(VoxelMapReach(0.5), 523776.0, 1e-6);
  const std::vector<Eigen::Vector3d> p = {{1.0, 2.0, 3.0},
                                          {reach_m - 1.0, 0.0, 0.0},
                                          {0.0, -reach_m - 1.0, 0.0},
                                          {500000.0, 5400000.0, 0.0},  // UTM, not in a local frame
                                          {NAN, 0.0, 0.0}};
  VoxelMap map(o);
  map.Insert(p);
  EXPECT_EQ(map.Size(), 2u);
  EXPECT_EQ(map.NumOutOfReach(), 2u);
  const Status s = CheckReach(map, p);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
  for (const char* part : {"2 of 5 points", "104.8 km", "0.1 m voxels", "500.0 x 5504.8 x 0.0 km"})
    EXPECT_NE(s.message().find(part), std::string::npos) << part << " not in: " << s.message();
  VoxelMap bulk(o);
  bulk.InsertInVoxelOrder(p, VoxelOrder(p, o.voxel_size));
  EXPECT_EQ(bulk.NumOutOfReach(), 2u);
  map.Clear();
  EXPECT_EQ(map.NumOutOfReach(), 0u);
  EXPECT_TRUE(CheckReach(map, {}).ok());
}

TEST(VoxelMap, ClearEmptiesTheMap) {
  VoxelMap map;
  std::mt19937 rng(1);
  map.Insert(RandomCloud(&rng, 1000, 5.0));
  EXPECT_GT(map.Size(), 0u);
  map.Clear();
  EXPECT_EQ(map.Size(), 0u);
  EXPECT_EQ(map.NumVoxels(), 0u);
  NeighborBuffer nb;
  EXPECT_EQ(map.KNearest(Eigen::Vector3d::Zero(), 3, 10.0, &nb), 0);
}



// Points and queries on a lattice aligned with the voxel faces (queries on
// faces, edges and corners: zero in-voxel offsets, many equal distances),
// sparse enough that most queries search deep shells with a loose limit.
// Two answers with the same points in the same order (ties included) and the
// same distances, bit for bit.
void ExpectSameAnswer(const NeighborBuffer& a, const NeighborBuffer& b) {
  ASSERT_EQ(a.size, b.size);
  for (int i = 0; i < a.size; ++i) {
    EXPECT_EQ(a.points[i], b.points[i]) << "rank " << i;
    EXPECT_EQ(a.dist2[i], b.dist2[i]) << "rank " << i;
  }
}

// Queries walking through random maps (consecutive queries close together,
// as the points of a scan) while the map changes between them: inserts that
// add voxels or only points, RemoveFar (which rebuilds the table and reuses
// freed blocks), Clear and assignment of another map. Every answer must agree
// with brute force over the stored points and equal, bit for bit and in
// order, the answer of a map freshly built from those points (which never
// saw a removal).
TEST(VoxelMap, KNearestMatchesBruteForceAndAFreshMapWhileTheMapChanges) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> step(0.0, 0.15);
  int checked = 0, full = 0, partial = 0, changes = 0;
  for (int trial = 0; trial < 60; ++trial) {
    MapOptions options;
    options.voxel_size = 0.2 + 0.8 * unit(rng);
    options.max_points_per_voxel = 1 + static_cast<int>(30 * unit(rng));
    options.min_point_distance = (trial % 3 == 0) ? 0.0 : 0.05 * unit(rng);
    const double half_extent = 2.0 + 8.0 * unit(rng);
    VoxelMap map(options);
    const VoxelMap other = [&] {
      VoxelMap m(options);
      m.Insert(RandomCloud(&rng, 500, half_extent));
      return m;
    }();
    map.Insert(RandomCloud(&rng, 200 + static_cast<int>(2000 * unit(rng)), half_extent));
    NeighborBuffer nb, fresh_nb;
    Eigen::Vector3d q = Eigen::Vector3d::Zero();
    for (int query = 0; query < 150; ++query) {
      q += Eigen::Vector3d(step(rng), step(rng), step(rng));
      if (q.cwiseAbs().maxCoeff() > 1.2 * half_extent) q.setZero();
      if (query % 25 == 5) {  // new points, most in new voxels
        map.Insert(RandomCloud(&rng, 100, half_extent));
        ++changes;
      } else if (query % 25 == 10 || query % 25 == 18) {
        map.RemoveFar(q, 0.3 * half_extent + 2.0 * options.voxel_size * unit(rng));
        ++changes;
      } else if (query % 25 == 20 && trial % 4 == 0) {
        map.Clear();
        map.Insert(RandomCloud(&rng, 300, half_extent));
        ++changes;
      } else if (query % 25 == 20 && trial % 4 == 1) {
        map = other;
        ++changes;
      }
      const int k = 1 + query % 10;
      const double max_dist = (query % 6 == 0) ? 3.0 * options.voxel_size : 0.1 + 2.0 * unit(rng);
      const int found = map.KNearest(q, k, max_dist, &nb);
      const std::vector<Eigen::Vector3d> stored = map.Points();
      VoxelMap fresh(options);
      fresh.Insert(stored);
      ASSERT_EQ(fresh.Size(), map.Size());
      ASSERT_EQ(fresh.KNearest(q, k, max_dist, &fresh_nb), found) << "trial " << trial;
      ExpectSameAnswer(fresh_nb, nb);
      if (NearBoundary(stored, q, max_dist)) continue;
      const std::vector<double> expected = BruteForce(stored, q, k, max_dist);
      ASSERT_EQ(found, static_cast<int>(expected.size())) << "trial " << trial;
      for (int i = 0; i < found; ++i)
        EXPECT_NEAR(nb.dist2[i], expected[i], 1e-9 + 1e-6 * expected[i]) << "rank " << i;
      ++checked;
      if (found == k) ++full;
      if (found > 0 && found < k) ++partial;
    }
  }
  EXPECT_GT(checked, 8000);
  EXPECT_GT(full, 3000);
  EXPECT_GT(partial, 200);
  EXPECT_GT(changes, 400);
}

TEST(VoxelMap, LatticeQueriesOnVoxelFacesMatchBruteForce) {
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> cell(-12, 12);
  MapOptions options;
  options.voxel_size = 0.5;
  options.min_point_distance = 0.0;
  VoxelMap map(options);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 400; ++i)
    pts.emplace_back(0.25 * cell(rng), 0.25 * cell(rng), 0.25 * cell(rng));
  map.Insert(pts);
  const std::vector<Eigen::Vector3d> stored = map.Points();
  int checked = 0, deep = 0;
  for (int query = 0; query < 600; ++query) {
    const Eigen::Vector3d q(0.5 * cell(rng), 0.5 * cell(rng), 0.25 * cell(rng));
    const int k = 1 + query % 8;
    const double max_dist = 0.3 + 0.1 * (query % 25);  // up to 2.7 m: shells up to 6
    if (NearBoundary(stored, q, max_dist)) continue;
    NeighborBuffer nb;
    const std::vector<double> expected = BruteForce(stored, q, k, max_dist);
    ASSERT_EQ(map.KNearest(q, k, max_dist, &nb), static_cast<int>(expected.size()))
        << "query " << query;
    for (int i = 0; i < nb.size; ++i) EXPECT_NEAR(nb.dist2[i], expected[i], 1e-9);
    ++checked;
    if (!expected.empty() && expected.back() > 1.5 * 1.5) ++deep;
  }
  EXPECT_GT(checked, 300);
  EXPECT_GT(deep, 20);  // neighbours beyond 1.5 m: shells 4 and deeper searched
}


// InsertInVoxelOrder stores what InsertPoint called in the same order stores
// (the same points, counts and query results), whatever the order, the
// voxel cap and the point spacing; only the voxel order is its fast path.
TEST(VoxelMap, InsertInVoxelOrderEqualsInsertingOneByOne) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 24; ++trial) {
    MapOptions o;
    o.voxel_size = std::uniform_real_distribution<double>(0.2, 1.0)(rng);
    o.max_points_per_voxel = std::uniform_int_distribution<int>(1, 40)(rng);
    o.min_point_distance = trial % 3 == 0 ? 0.0 : 0.05;
    std::vector<Eigen::Vector3d> pts = RandomCloud(&rng, 3000, trial % 2 == 0 ? 1.5 : 6.0);
    pts.push_back(Eigen::Vector3d(NAN, 0.0, 0.0));  // unkeyable: skipped by both
    pts.push_back(Eigen::Vector3d(1e12, 0.0, 0.0));
    std::vector<uint32_t> order = VoxelOrder(pts, o.voxel_size);
    if (trial % 4 == 3) std::shuffle(order.begin(), order.end(), rng);  // any order is correct
    VoxelMap bulk(o), single(o);
    if (trial % 5 == 4) {  // into a map that already holds points
      const std::vector<Eigen::Vector3d> before = RandomCloud(&rng, 500, 2.0);
      bulk.Insert(before);
      single.Insert(before);
    }
    const size_t stored = bulk.InsertInVoxelOrder(pts, order);
    size_t stored_single = 0;
    for (uint32_t i : order) stored_single += single.InsertPoint(pts[i]) ? 1 : 0;
    ASSERT_EQ(stored, stored_single) << trial;
    ASSERT_EQ(bulk.Size(), single.Size()) << trial;
    ASSERT_EQ(bulk.NumVoxels(), single.NumVoxels()) << trial;
    ASSERT_EQ(bulk.NumOutOfReach(), single.NumOutOfReach()) << trial;
    EXPECT_EQ(bulk.NumOutOfReach(), 1u) << trial;  // 1e12 m; the NaN is not counted
    NeighborBuffer a, b;
    for (const Eigen::Vector3d& q : RandomCloud(&rng, 200, 3.0)) {
      ASSERT_EQ(bulk.KNearest(q, 8, 2.0, &a), single.KNearest(q, 8, 2.0, &b)) << trial;
      for (int k = 0; k < a.size; ++k) {
        EXPECT_EQ(a.points[k], b.points[k]) << trial;
        EXPECT_EQ(a.dist2[k], b.dist2[k]) << trial;
      }
    }
  }
}

}  // namespace
}  // namespace rvlio

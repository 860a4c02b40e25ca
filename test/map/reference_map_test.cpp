#include "rvlio/map/reference_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/common/cpu_time.h"
#include "rvlio/math/local_origin.h"

namespace rvlio {
namespace {

std::vector<Eigen::Vector3d> RandomCloud(int n, double extent_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-extent_m, extent_m);
  std::vector<Eigen::Vector3d> p(n);
  for (Eigen::Vector3d& x : p) x = Eigen::Vector3d(u(rng), u(rng), u(rng));
  return p;
}

TEST(ReferenceMap, KeepsEveryPointIncludingDuplicatesAndDenseVoxels) {
  std::vector<Eigen::Vector3d> p = RandomCloud(3000, 0.05, 1);  // all in a few voxels
  p.push_back(p[0]);                                             // a duplicate
  const ReferenceMap map(p);
  EXPECT_EQ(map.Size(), p.size());
  EXPECT_EQ(map.NumSkipped(), 0u);
}

TEST(ReferenceMap, SkipsNonFinitePointsAndCountsThem) {
  std::vector<Eigen::Vector3d> p = RandomCloud(100, 1.0, 2);
  p.push_back(Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 0));
  p.push_back(Eigen::Vector3d(0, std::numeric_limits<double>::infinity(), 0));
  const ReferenceMap map(p);
  EXPECT_EQ(map.Size(), 100u);
  EXPECT_EQ(map.NumSkipped(), 2u);
  EXPECT_TRUE(map.Bounds().contains(Eigen::Vector3d(0.0, 0.0, 0.0)));
}

// At UTM coordinates (northing 5.4e6 m = 5.4e7 voxels of 0.1 m) not a point
// fits the packed keys, and a float32 keeps only decimetres; in the cloud's
// local frame (math/local_origin.h) every point is stored, to the micrometre.
TEST(ReferenceMap, ASurveyInANationalGridFitsInItsLocalFrame) {
  const Eigen::Vector3d utm(500000.0, 5400000.0, 0.0);
  std::vector<Eigen::Vector3d> p = RandomCloud(2000, 20.0, 3);
  for (Eigen::Vector3d& x : p) x += utm;
  const ReferenceMap as_given(p);
  EXPECT_EQ(as_given.Size(), 0u);
  EXPECT_EQ(as_given.NumOutOfReach(), p.size());
  const LocalOrigin origin = ChooseLocalOrigin(p);
  EXPECT_EQ(origin.t_user_local, utm);
  origin.ToLocal(&p);
  const ReferenceMap local(p);
  EXPECT_EQ(local.Size(), p.size());
  EXPECT_EQ(local.NumOutOfReach(), 0u);
  NeighborBuffer nb;
  ASSERT_EQ(local.KNearest(p[17], 1, 0.1, &nb), 1);
  EXPECT_LT(std::sqrt(nb.dist2[0]), 1e-5);
}

// Exact k nearest against brute force over the float-rounded points.
TEST(ReferenceMap, KNearestMatchesBruteForce) {
  const std::vector<Eigen::Vector3d> p = RandomCloud(5000, 2.0, 3);
  const ReferenceMap map(p, ReferenceMapOptions{0.1});
  const std::vector<Eigen::Vector3d> queries = RandomCloud(200, 2.5, 4);
  NeighborBuffer nb;
  for (const Eigen::Vector3d& q : queries) {
    std::vector<double> d2;
    for (const Eigen::Vector3d& x : p) d2.push_back((x.cast<float>().cast<double>() - q).squaredNorm());
    std::sort(d2.begin(), d2.end());
    const double max_dist = 0.3;
    const int n = map.KNearest(q, 8, max_dist, &nb);
    int expected = 0;
    while (expected < 8 && d2[expected] <= max_dist * max_dist) ++expected;
    ASSERT_EQ(n, expected);
    for (int i = 0; i < n; ++i) EXPECT_NEAR(nb.dist2[i], d2[i], 1e-6);
  }
}

// Points on the plane z = 0 over [-extent, extent]^2.
std::vector<Eigen::Vector3d> PlaneCloud(int n, double extent_m, unsigned seed) {
  std::vector<Eigen::Vector3d> p = RandomCloud(n, extent_m, seed);
  for (Eigen::Vector3d& x : p) x.z() = 0.0;
  return p;
}

// The search radius beyond which the shells around a query cover more
// voxels than the map has slots: queries with neighbours close by still end
// after a few shells (the cost does not follow max_dist), the others scan
// every voxel; both are exact.
TEST(ReferenceMap, KNearestCostDoesNotFollowALargeRadius) {
  const std::vector<Eigen::Vector3d> p = PlaneCloud(30000, 2.0, 5);
  const ReferenceMap map(p, ReferenceMapOptions{0.1});
  const std::vector<Eigen::Vector3d> near = PlaneCloud(30000, 2.0, 6);
  auto cpu_ms = [&](double max_dist) {
    NeighborBuffer nb;
    const double t0 = ThreadCpuMs();
    int found = 0;
    for (const Eigen::Vector3d& q : near) found += map.KNearest(q, 8, max_dist, &nb);
    EXPECT_EQ(found, 8 * static_cast<int>(near.size()));
    return ThreadCpuMs() - t0;
  };
  const double small_ms = cpu_ms(0.3);
  const double large_ms = cpu_ms(1000.0);
  EXPECT_LT(large_ms, 3.0 * small_ms + 30.0) << small_ms << " ms at 0.3 m";

  // Exact on both paths: settled by the shells, and a query 3 m off the
  // plane that they leave open (a scan of every voxel).
  NeighborBuffer nb;
  for (const Eigen::Vector3d& q : {Eigen::Vector3d(0.3, -0.2, 0.01), Eigen::Vector3d(0.5, 0.5, 3.0),
                                   Eigen::Vector3d(9.0, 0.0, 0.0)}) {
    std::vector<double> d2;
    for (const Eigen::Vector3d& x : p) d2.push_back((x.cast<float>().cast<double>() - q).squaredNorm());
    std::sort(d2.begin(), d2.end());
    ASSERT_EQ(map.KNearest(q, 8, 1000.0, &nb), 8);
    for (int i = 0; i < 8; ++i) EXPECT_NEAR(nb.dist2[i], d2[i], 1e-4) << q.transpose();
  }
}

}  // namespace
}  // namespace rvlio

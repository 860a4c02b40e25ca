#include "rvlio/map/reference_map.h"

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace rvlio

#include "rvlio/map/reference_map.h"

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

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

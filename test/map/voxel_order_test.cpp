// VoxelOrder (map/voxel_order.h): a stable sort of point indices by voxel.
#include "rvlio/map/voxel_order.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/map/voxel_key.h"

namespace rvlio {
namespace {

std::tuple<int32_t, int32_t, int32_t> Key(const Eigen::Vector3d& p, double voxel_m) {
  const VoxelKey k = KeyOf(p, 1.0 / voxel_m);
  return {k.x, k.y, k.z};
}

TEST(VoxelOrder, IsAStableSortByVoxelWithUnkeyablePointsLast) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < 20000; ++i) p.emplace_back(u(rng), u(rng), 0.2 * u(rng));
  p.push_back(p[17]);                                                    // a duplicate
  p.emplace_back(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);   // index 20001
  p.emplace_back(1e12, 0.0, 0.0);                                        // too far to key
  p.emplace_back(-1e5, 2e5, -3e5);                                       // far but keyable
  const double voxel_m = 0.1;
  const std::vector<uint32_t> order = VoxelOrder(p, voxel_m);
  ASSERT_EQ(order.size(), p.size());
  std::vector<uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (uint32_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);  // a permutation
  EXPECT_EQ(order[order.size() - 2], 20001u);
  EXPECT_EQ(order.back(), 20002u);
  for (size_t j = 1; j + 2 < order.size(); ++j) {
    const auto a = Key(p[order[j - 1]], voxel_m), b = Key(p[order[j]], voxel_m);
    ASSERT_TRUE(a < b || (a == b && order[j - 1] < order[j])) << j;
  }
}

TEST(VoxelOrder, EmptyAndAllUnkeyableClouds) {
  EXPECT_TRUE(VoxelOrder({}, 0.1).empty());
  const std::vector<Eigen::Vector3d> nan(3, Eigen::Vector3d::Constant(std::nan("")));
  EXPECT_EQ(VoxelOrder(nan, 0.1), (std::vector<uint32_t>{0, 1, 2}));
}

}  // namespace
}  // namespace rvlio

#include "rvlio/map/output_map.h"

#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include <gtest/gtest.h>

namespace rvlio {
namespace {

TEST(OutputMap, OneCentroidPerVoxel) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  const double res = 0.7;
  OutputMap map(res);
  // Reference: plain std::map of voxel -> (sum, count).
  std::map<std::tuple<int, int, int>, std::pair<Eigen::Vector3d, int>> ref;
  for (int batch = 0; batch < 5; ++batch) {
    std::vector<Eigen::Vector3d> pts(2000);
    for (auto& p : pts) {
      p = Eigen::Vector3d(u(rng), u(rng), u(rng));
      const auto key = std::make_tuple(static_cast<int>(std::floor(p.x() / res)),
                                       static_cast<int>(std::floor(p.y() / res)),
                                       static_cast<int>(std::floor(p.z() / res)));
      auto it = ref.emplace(key, std::make_pair(Eigen::Vector3d::Zero().eval(), 0)).first;
      it->second.first += p;
      it->second.second += 1;
    }
    map.Insert(pts);
  }
  ASSERT_EQ(map.Size(), ref.size());
  const std::vector<Eigen::Vector3d> out = map.Points();
  ASSERT_EQ(out.size(), ref.size());
  for (const auto& c : out) {
    const auto key = std::make_tuple(static_cast<int>(std::floor(c.x() / res)),
                                     static_cast<int>(std::floor(c.y() / res)),
                                     static_cast<int>(std::floor(c.z() / res)));
    auto it = ref.find(key);
    ASSERT_NE(it, ref.end()) << "centroid left its voxel";
    EXPECT_LT((c - it->second.first / it->second.second).norm(), 1e-12);
    ref.erase(it);  // one point per voxel
  }
  EXPECT_TRUE(ref.empty());
}

TEST(OutputMap, IgnoresNonFinitePoints) {
  OutputMap map(0.2);
  map.Insert({Eigen::Vector3d(NAN, 0, 0), Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1.01, 2, 3)});
  ASSERT_EQ(map.Size(), 1u);
  EXPECT_NEAR(map.Points()[0].x(), 1.005, 1e-12);
}

}  // namespace
}  // namespace rvlio

#include "rvlio/map/output_map.h"

#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include <gtest/gtest.h>

namespace rvlio {
namespace {

using VoxelIndex = std::tuple<int, int, int>;

VoxelIndex VoxelOf(const Eigen::Vector3d& p, double res) {
  return {static_cast<int>(std::floor(p.x() / res)), static_cast<int>(std::floor(p.y() / res)),
          static_cast<int>(std::floor(p.z() / res))};
}

double CentreDistance2(const Eigen::Vector3d& p, double res) {
  const auto [i, j, k] = VoxelOf(p, res);
  return (p - Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5) * res).squaredNorm();
}

// Scans of random returns, each with its own intensity, time and ring.
struct RandomScans {
  std::vector<Scan> scans;
  std::vector<std::vector<Eigen::Vector3d>> p_world;
};

RandomScans MakeScans(int count, int points, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-5.0, 5.0), v(0.0, 255.0);
  RandomScans r;
  for (int s = 0; s < count; ++s) {
    Scan scan;
    scan.has_intensity = scan.has_ring = true;
    std::vector<Eigen::Vector3d> p(static_cast<size_t>(points));
    for (int i = 0; i < points; ++i) {
      p[i] = Eigen::Vector3d(u(rng), u(rng), u(rng));
      LidarPoint q;
      q.intensity = static_cast<float>(v(rng));
      q.t_ns = 1'700'000'000'000'000'000 + 100'000'000LL * s + 1000 * i;
      q.ring = static_cast<uint16_t>(i % 64);
      scan.points.push_back(q);
    }
    r.scans.push_back(std::move(scan));
    r.p_world.push_back(std::move(p));
  }
  return r;
}

// Against a plain std::map of voxel -> (sum, count, nearest return): one
// point per voxel at the centroid of what fell into it, with the attributes
// of the return nearest the voxel's centre (the earlier of equals).
TEST(OutputMap, OneCentroidPerVoxelWithTheAttributesOfTheReturnNearestItsCentre) {
  const double res = 0.7;
  const RandomScans in = MakeScans(5, 2000, 11);
  OutputMap map(res);
  struct Kept {
    double d2;
    const LidarPoint* q;
    uint32_t scan;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
  };
  std::map<VoxelIndex, Kept> ref;
  for (size_t s = 0; s < in.scans.size(); ++s) {
    map.InsertScan(in.p_world[s], in.scans[s], static_cast<uint32_t>(s));
    for (size_t i = 0; i < in.p_world[s].size(); ++i) {
      const Eigen::Vector3d& p = in.p_world[s][i];
      const Kept k{CentreDistance2(p, res), &in.scans[s].points[i], static_cast<uint32_t>(s)};
      auto [it, created] = ref.emplace(VoxelOf(p, res), k);
      Kept& kept = it->second;
      kept.sum += p;
      ++kept.count;
      if (!created && static_cast<float>(k.d2) < static_cast<float>(kept.d2)) {
        kept.d2 = k.d2;
        kept.q = k.q;
        kept.scan = k.scan;
      }
    }
  }
  const MapCloud cloud = map.Cloud();
  ASSERT_TRUE(cloud.Consistent());
  EXPECT_TRUE(cloud.has_intensity && cloud.has_time && cloud.has_ring && cloud.has_scan_index);
  ASSERT_EQ(cloud.size(), ref.size());
  EXPECT_EQ(map.Points(), cloud.p);
  for (size_t i = 0; i < cloud.size(); ++i) {
    auto it = ref.find(VoxelOf(cloud.p[i], res));
    ASSERT_NE(it, ref.end()) << "centroid left its voxel";
    const Kept& k = it->second;
    EXPECT_LT((cloud.p[i] - k.sum / k.count).norm(), 1e-12);
    EXPECT_EQ(cloud.intensity[i], k.q->intensity);
    EXPECT_EQ(cloud.t_ns[i], k.q->t_ns);
    EXPECT_EQ(cloud.ring[i], k.q->ring);
    EXPECT_EQ(cloud.scan_index[i], k.scan);
    ref.erase(it);  // one point per voxel
  }
  EXPECT_TRUE(ref.empty());
}

TEST(OutputMap, AnAttributeOnlyWhenEveryInsertionGaveIt) {
  RandomScans in = MakeScans(2, 50, 3);
  OutputMap map(0.5);
  EXPECT_FALSE(map.Cloud().has_time);  // nothing inserted: nothing known
  in.scans[1].has_intensity = false;   // e.g. a layout without intensity
  map.InsertScan(in.p_world[0], in.scans[0], 0);
  EXPECT_TRUE(map.Cloud().has_intensity);
  map.InsertScan(in.p_world[1], in.scans[1], 1);
  const MapCloud cloud = map.Cloud();
  EXPECT_TRUE(cloud.Consistent());
  EXPECT_FALSE(cloud.has_intensity);
  EXPECT_TRUE(cloud.intensity.empty()) << "absent, not zero";
  EXPECT_TRUE(cloud.has_ring && cloud.has_time && cloud.has_scan_index);
  map.Insert(in.p_world[0]);  // points without attributes
  const MapCloud bare = map.Cloud();
  EXPECT_FALSE(bare.has_ring || bare.has_time || bare.has_scan_index || bare.has_intensity);
  EXPECT_TRUE(bare.Consistent());
}

TEST(OutputMap, InsertCloudKeepsTheCloudsAttributes) {
  const RandomScans in = MakeScans(3, 300, 5);
  OutputMap a(0.4);
  for (size_t s = 0; s < in.scans.size(); ++s)
    a.InsertScan(in.p_world[s], in.scans[s], static_cast<uint32_t>(s));
  const MapCloud first = a.Cloud();
  // Re-voxelizing a map at its own resolution keeps it as it is (merge).
  OutputMap b(0.4);
  b.InsertCloud(first);
  EXPECT_EQ(b.Cloud(), first);
}

TEST(OutputMap, IgnoresNonFinitePoints) {
  OutputMap map(0.2);
  map.Insert({Eigen::Vector3d(NAN, 0, 0), Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1.01, 2, 3)});
  ASSERT_EQ(map.Size(), 1u);
  EXPECT_NEAR(map.Points()[0].x(), 1.005, 1e-12);
}

}  // namespace
}  // namespace rvlio

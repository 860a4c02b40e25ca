#include "rvlio/lidar/preprocess.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <tuple>

#include <gtest/gtest.h>

namespace rvlio {
namespace {

Scan RandomScan(std::mt19937* rng, int n, double extent) {
  std::uniform_real_distribution<float> u(-extent, extent);
  Scan scan;
  scan.t_start_ns = 1000;
  scan.t_end_ns = 1000 + 100000000;
  for (int i = 0; i < n; ++i) {
    LidarPoint p;
    p.p_lidar = Eigen::Vector3f(u(*rng), u(*rng), u(*rng));
    p.t_ns = scan.t_start_ns + i * 1000;
    p.ring = static_cast<uint16_t>(i % 32);
    p.intensity = static_cast<float>(i);
    scan.points.push_back(p);
  }
  return scan;
}

using Key = std::tuple<int, int, int>;
Key KeyOfPoint(const Eigen::Vector3f& p, double s) {
  const Eigen::Vector3d q = p.cast<double>();
  return Key(static_cast<int>(std::floor(q.x() / s)), static_cast<int>(std::floor(q.y() / s)),
             static_cast<int>(std::floor(q.z() / s)));
}

// Reference: the point nearest each voxel centre among strided, in-range points.
TEST(Preprocess, OnePointPerVoxelNearestTheCentre) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  LidarOptions options;
  for (int trial = 0; trial < 60; ++trial) {
    options.voxel_size = 0.1 + 2.0 * unit(rng);
    options.min_range = 2.0 * unit(rng);
    options.max_range = options.min_range + 1.0 + 20.0 * unit(rng);
    options.point_stride = 1 + trial % 3;
    ScanPreprocessor p(options);
    const Scan scan = RandomScan(&rng, 200 + static_cast<int>(20000 * unit(rng)), 25.0);
    // The workspace is reused: a previous scan must leave nothing behind.
    std::vector<int> indices;
    p.SelectIndices(RandomScan(&rng, 5000, 25.0), &indices);

    std::map<Key, int> best;
    int in_range = 0;
    for (int i = 0; i < static_cast<int>(scan.points.size()); ++i) {
      if (i % options.point_stride != 0) continue;
      const double r = scan.points[i].p_lidar.cast<double>().norm();
      if (r < options.min_range || r > options.max_range) continue;
      ++in_range;
      const Key k = KeyOfPoint(scan.points[i].p_lidar, options.voxel_size);
      const Eigen::Vector3d centre =
          (Eigen::Vector3d(std::get<0>(k), std::get<1>(k), std::get<2>(k)).array() + 0.5) *
          options.voxel_size;
      auto dist = [&](int j) { return (scan.points[j].p_lidar.cast<double>() - centre).norm(); };
      auto it = best.find(k);
      if (it == best.end() || dist(i) < dist(it->second) - 1e-6) best[k] = i;
    }

    p.SelectIndices(scan, &indices);
    ASSERT_EQ(indices.size(), best.size()) << "trial " << trial;
    EXPECT_TRUE(std::is_sorted(indices.begin(), indices.end()));
    std::map<Key, int> got;
    for (const int i : indices) {
      const double r = scan.points[i].p_lidar.cast<double>().norm();
      EXPECT_GE(r, options.min_range);
      EXPECT_LE(r, options.max_range);
      EXPECT_EQ(i % options.point_stride, 0);
      EXPECT_TRUE(got.emplace(KeyOfPoint(scan.points[i].p_lidar, options.voxel_size), i).second)
          << "two points in one voxel";
    }
    for (const auto& [k, i] : best) {
      ASSERT_TRUE(got.count(k));
      // Same point, or one equally near the centre (float ties).
      const Eigen::Vector3d centre =
          (Eigen::Vector3d(std::get<0>(k), std::get<1>(k), std::get<2>(k)).array() + 0.5) *
          options.voxel_size;
      EXPECT_NEAR((scan.points[got[k]].p_lidar.cast<double>() - centre).norm(),
                  (scan.points[i].p_lidar.cast<double>() - centre).norm(), 1e-5);
    }
    const PreprocessStats& s = p.stats();
    EXPECT_EQ(s.num_input, static_cast<int>(scan.points.size()));
    EXPECT_EQ(s.num_output, static_cast<int>(indices.size()));
    EXPECT_EQ(s.num_input - s.num_strided_out - s.num_invalid - s.num_out_of_range, in_range);
  }
}

// A ring-major sweep (rows of columns, like an organized Ouster cloud) with
// coordinates on a 1 cm grid (exact distance ties), repeated points, gaps
// (zero points), non-finite and far points.
Scan SweepWithTies(std::mt19937* rng, int rows, int cols) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Scan scan;
  scan.t_end_ns = 100000000;
  for (int r = 0; r < rows; ++r) {
    const double el = -0.4 + 0.8 * r / std::max(1, rows - 1);
    for (int c = 0; c < cols; ++c) {
      const double az = 2.0 * M_PI * c / cols;
      const double range = 2.0 + 30.0 * u(*rng) * u(*rng);
      Eigen::Vector3d p(range * std::cos(el) * std::cos(az), range * std::cos(el) * std::sin(az),
                        range * std::sin(el));
      p = (p * 100.0).array().round() / 100.0;
      LidarPoint pt;
      pt.p_lidar = p.cast<float>();
      pt.t_ns = c * 1000;
      const double roll = u(*rng);
      if (roll < 0.05) pt.p_lidar.setZero();                                   // no return
      if (roll > 0.98) pt.p_lidar.x() = std::numeric_limits<float>::quiet_NaN();
      if (roll > 0.97 && roll <= 0.98) pt.p_lidar *= 100.0f;                   // beyond max_range
      if (roll > 0.9 && roll <= 0.97 && !scan.points.empty())
        pt.p_lidar = scan.points.back().p_lidar;                               // exact repeat
      scan.points.push_back(pt);
    }
  }
  return scan;
}

// Exact reference of the documented rule: per voxel the point with the
// smallest squared distance to the centre (float, as documented), the
// earliest on ties; ascending indices.
std::vector<int> ReferenceIndices(const Scan& scan, const LidarOptions& o) {
  std::map<Key, std::pair<float, int>> best;
  const double inv = 1.0 / o.voxel_size;
  for (int i = 0; i < static_cast<int>(scan.points.size()); i += o.point_stride) {
    const Eigen::Vector3d p = scan.points[i].p_lidar.cast<double>();
    if (!p.allFinite()) continue;
    const double r2 = p.squaredNorm();
    if (r2 < o.min_range * o.min_range || r2 > o.max_range * o.max_range) continue;
    const VoxelKey k = KeyOf(p, inv);
    const Eigen::Vector3d centre((k.x + 0.5) * o.voxel_size, (k.y + 0.5) * o.voxel_size,
                                 (k.z + 0.5) * o.voxel_size);
    const float d2 = static_cast<float>((p - centre).squaredNorm());
    auto [it, added] = best.emplace(Key(k.x, k.y, k.z), std::make_pair(d2, i));
    if (!added && d2 < it->second.first) it->second = std::make_pair(d2, i);
  }
  std::vector<int> out;
  for (const auto& [k, v] : best) out.push_back(v.second);
  std::sort(out.begin(), out.end());
  return out;
}

TEST(Preprocess, SweepMatchesExactReferenceIncludingTies) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 24; ++trial) {
    LidarOptions options;
    options.voxel_size = (trial % 4 == 0) ? 0.05 : 0.1 + 0.2 * (trial % 6);
    options.min_range = 0.5 + 0.5 * (trial % 3);
    options.max_range = 20.0 + 10.0 * (trial % 4);
    options.point_stride = 1 + trial % 3;
    ScanPreprocessor pre(options);
    std::vector<int> indices;
    // Several sweeps through the same preprocessor (table reuse and growth).
    for (int sweep = 0; sweep < 3; ++sweep) {
      const Scan scan = SweepWithTies(&rng, 16, 256 + 256 * sweep);
      pre.SelectIndices(scan, &indices);
      const std::vector<int> expected = ReferenceIndices(scan, options);
      ASSERT_GT(expected.size(), 50u);
      ASSERT_EQ(indices, expected) << "trial " << trial << " sweep " << sweep;
      EXPECT_EQ(pre.stats().num_output, static_cast<int>(expected.size()));
    }
  }
}

// Clouds in random order (no sweep structure, so consecutive points rarely
// share a voxel) with NaN, +-Inf, no-return, near and far points: the kept
// indices match the reference and the drop counts match a direct count,
// also with a max_range whose square overflows to +Inf.
TEST(Preprocess, RandomCloudsMatchReferenceAndCountDrops) {
  std::mt19937 rng(18);
  std::uniform_real_distribution<float> coord(-40.0f, 40.0f);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const float inf = std::numeric_limits<float>::infinity();
  for (int trial = 0; trial < 60; ++trial) {
    LidarOptions options;
    options.voxel_size = 0.2 + 0.1 * (trial % 7);
    options.min_range = 0.5 * (trial % 3);
    options.max_range = trial % 5 == 0 ? 1e200 : 30.0 + 5.0 * (trial % 4);
    options.point_stride = 1 + trial % 2;
    // Far points: beyond max_range, or (huge max_range) still keyable voxels.
    const float far_scale = trial % 5 == 0 ? 1e3f : 1e30f;
    Scan scan;
    const int n = 500 + static_cast<int>(rng() % 3000);
    for (int i = 0; i < n; ++i) {
      LidarPoint pt;
      pt.p_lidar = Eigen::Vector3f(coord(rng), coord(rng), 0.2f * coord(rng));
      const double roll = u(rng);
      if (roll < 0.02) pt.p_lidar.y() = std::numeric_limits<float>::quiet_NaN();
      else if (roll < 0.04) pt.p_lidar.z() = (roll < 0.03 ? inf : -inf);
      else if (roll < 0.06) pt.p_lidar.setZero();
      else if (roll < 0.08) pt.p_lidar *= far_scale;
      pt.t_ns = i;
      scan.points.push_back(pt);
    }
    int invalid = 0, out_of_range = 0;
    for (int i = 0; i < n; i += options.point_stride) {
      const Eigen::Vector3d p = scan.points[i].p_lidar.cast<double>();
      const double r2 = p.squaredNorm();
      if (!p.allFinite()) ++invalid;
      else if (r2 < options.min_range * options.min_range ||
               r2 > options.max_range * options.max_range) ++out_of_range;
    }
    ScanPreprocessor pre(options);
    std::vector<int> indices;
    pre.SelectIndices(scan, &indices);
    const std::vector<int> expected = ReferenceIndices(scan, options);
    ASSERT_GT(expected.size(), 50u);
    ASSERT_EQ(indices, expected) << "trial " << trial;
    EXPECT_EQ(pre.stats().num_invalid, invalid) << "trial " << trial;
    EXPECT_EQ(pre.stats().num_out_of_range, out_of_range) << "trial " << trial;
    EXPECT_EQ(pre.stats().num_output, static_cast<int>(expected.size())) << "trial " << trial;
  }
}

TEST(Preprocess, VoxelSizeZeroKeepsEveryPointInRange) {
  std::mt19937 rng(2);
  LidarOptions options;
  options.voxel_size = 0.0;
  options.min_range = 5.0;
  options.max_range = 15.0;
  ScanPreprocessor pre(options);
  const Scan scan = RandomScan(&rng, 5000, 20.0);
  std::vector<int> indices;
  pre.SelectIndices(scan, &indices);
  int expected = 0;
  for (const auto& p : scan.points) {
    const double r = p.p_lidar.cast<double>().norm();
    expected += (r >= 5.0 && r <= 15.0);
  }
  EXPECT_EQ(static_cast<int>(indices.size()), expected);
  EXPECT_GT(expected, 500);
}

TEST(Preprocess, DownsampleCopiesPointsWithTheirTimes) {
  std::mt19937 rng(3);
  Scan scan = RandomScan(&rng, 3000, 10.0);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  scan.points[5].p_lidar.x() = nan;
  scan.points[6].p_lidar.y() = std::numeric_limits<float>::infinity();
  LidarOptions options;
  options.voxel_size = 1.0;
  options.min_range = 0.0;
  ScanPreprocessor pre(options);
  Scan out;
  pre.Downsample(scan, &out);
  std::vector<int> indices;
  pre.SelectIndices(scan, &indices);
  ASSERT_EQ(out.points.size(), indices.size());
  EXPECT_EQ(out.t_start_ns, scan.t_start_ns);
  EXPECT_EQ(out.t_end_ns, scan.t_end_ns);
  EXPECT_EQ(pre.stats().num_invalid, 2);
  for (size_t j = 0; j < indices.size(); ++j) {
    const LidarPoint& a = out.points[j];
    const LidarPoint& b = scan.points[indices[j]];
    EXPECT_EQ(a.p_lidar, b.p_lidar);
    EXPECT_EQ(a.t_ns, b.t_ns);
    EXPECT_EQ(a.ring, b.ring);
    EXPECT_EQ(a.intensity, b.intensity);
    EXPECT_TRUE(a.p_lidar.allFinite());
  }
  // Repeated use of the same preprocessor gives the same answer.
  Scan again;
  pre.Downsample(scan, &again);
  ASSERT_EQ(again.points.size(), out.points.size());
  for (size_t j = 0; j < out.points.size(); ++j)
    EXPECT_EQ(again.points[j].t_ns, out.points[j].t_ns);
}

TEST(Preprocess, EmptyScan) {
  ScanPreprocessor pre{LidarOptions()};
  std::vector<int> indices = {1, 2, 3};
  pre.SelectIndices(Scan(), &indices);
  EXPECT_TRUE(indices.empty());
  EXPECT_EQ(pre.stats().num_output, 0);
}

}  // namespace
}  // namespace rvlio

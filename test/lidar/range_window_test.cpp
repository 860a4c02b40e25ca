// The range window (lidar/range_window.h), the one definition of the range
// crop that the decoders and the scan preprocessor apply.
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/lidar/preprocess.h"
#include "rvlio/lidar/range_window.h"

namespace rvlio {
namespace {

LidarOptions Range(double min_m, double max_m) {
  LidarOptions o;
  o.min_range = min_m;
  o.max_range = max_m;
  return o;
}

TEST(RangeWindow, BoundsAreInclusiveAndNonFiniteRangesAreOutside) {
  const RangeWindow w(Range(0.5, 100.0));
  EXPECT_TRUE(w.Contains(0.25));    // 0.5 m
  EXPECT_TRUE(w.Contains(1.0e4));   // 100 m
  EXPECT_FALSE(w.Contains(0.2499));
  EXPECT_FALSE(w.Contains(1.0001e4));
  EXPECT_FALSE(w.Contains(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_FALSE(w.Contains(std::numeric_limits<double>::infinity()));
  // "No crop" as bag_info configures it: every finite range is inside.
  const RangeWindow all(Range(0.0, std::numeric_limits<double>::max()));
  EXPECT_TRUE(all.Contains(0.0));
  EXPECT_TRUE(all.Contains(1e300));
  EXPECT_FALSE(all.Contains(std::numeric_limits<double>::infinity()));
}

// The preprocessor keeps exactly the points inside the window (grid off,
// stride 1), over random points around both bounds.
TEST(RangeWindow, ThePreprocessorKeepsExactlyThePointsInsideTheWindow) {
  LidarOptions o = Range(1.0, 20.0);
  o.voxel_size = 0.0;
  o.point_stride = 1;
  const RangeWindow w(o);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coord(-25.0f, 25.0f);
  Scan scan;
  for (int i = 0; i < 2000; ++i) {
    LidarPoint p;
    p.p_lidar = Eigen::Vector3f(coord(rng), coord(rng), 0.1f * coord(rng));
    if (i % 50 == 0) p.p_lidar = p.p_lidar.normalized() * (i % 100 == 0 ? 1.0f : 20.0f);
    p.t_ns = i;
    scan.points.push_back(p);
  }
  ScanPreprocessor pre(o);
  std::vector<int> kept;
  pre.SelectIndices(scan, &kept);
  size_t expected = 0, k = 0;
  for (size_t i = 0; i < scan.points.size(); ++i) {
    const bool inside = w.Contains(scan.points[i].p_lidar.cast<double>().squaredNorm());
    expected += inside;
    if (inside) {
      ASSERT_LT(k, kept.size());
      EXPECT_EQ(kept[k++], static_cast<int>(i));
    }
  }
  EXPECT_EQ(kept.size(), expected);
  EXPECT_EQ(pre.stats().num_out_of_range, static_cast<int>(scan.points.size() - expected));
  EXPECT_GT(expected, 100u);
  EXPECT_LT(expected, scan.points.size());
}

}  // namespace
}  // namespace rvlio

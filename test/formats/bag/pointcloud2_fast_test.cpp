// The fast path of DecodePointCloud2 (common Ouster and Velodyne layouts)
// against the generic reader (DecodePointCloud2Generic): same points, bit for
// bit, same statistics; every other layout falls back to the generic reader.
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "cloud_builder.h"
#include "rvlio/formats/pointcloud2.h"

namespace rvlio {
namespace {

using test::RawCloud;

constexpr TimeNs kStamp = 1700000000123456789LL;

struct Case {
  std::string name;
  RawCloud cloud;
  bool fast;  // the fast path must take it
};

// The field `name` with another datatype (and the same offset).
RawCloud Retyped(RawCloud c, const std::string& name, uint8_t datatype) {
  for (PointField& f : c.fields)
    if (f.name == name) f.datatype = datatype;
  return c;
}

RawCloud Without(RawCloud c, const std::string& name) {
  for (size_t i = 0; i < c.fields.size(); ++i)
    if (c.fields[i].name == name) c.fields.erase(c.fields.begin() + i);
  if (c.ring_field == name) c.ring_field.clear();
  return c;
}

std::vector<Case> Cases() {
  RawCloud big = test::OusterCloud();
  big.is_bigendian = true;
  RawCloud velodyne_f64 = test::VelodyneCloud();  // time float64 at offset 24
  velodyne_f64.point_step = 40;
  velodyne_f64 = Retyped(velodyne_f64, "time", kPointFloat64);
  RawCloud x_f64 = test::HesaiCloud();  // x float64: the fast path needs float32
  x_f64.fields = {{"x", 0, kPointFloat64, 1},  {"y", 8, kPointFloat32, 1},
                  {"z", 12, kPointFloat32, 1}, {"intensity", 16, kPointFloat32, 1},
                  {"t", 20, kPointUint32, 1},  {"ring", 26, kPointUint16, 1}};
  x_f64.time_field = "t";
  return {
      {"ouster", test::OusterCloud(), true},
      {"ouster_ring_u8", Retyped(test::OusterCloud(), "ring", kPointUint8), true},
      {"ouster_no_ring", Without(test::OusterCloud(), "ring"), true},
      {"ouster_no_intensity", Without(test::OusterCloud(), "intensity"), true},
      {"velodyne", test::VelodyneCloud(), true},
      {"velodyne_no_ring_no_intensity",
       Without(Without(test::VelodyneCloud(), "ring"), "intensity"), true},
      {"livox_offset_time", test::LivoxOffsetCloud(), true},  // uint32 ns, line uint8
      // Odd layouts: the generic reader.
      {"ouster_big_endian", big, false},
      {"ouster_t_int32", Retyped(test::OusterCloud(), "t", kPointInt32), false},
      {"ouster_t_float32", Retyped(test::OusterCloud(), "t", kPointFloat32), false},
      {"ouster_intensity_u16", Retyped(test::OusterCloud(), "intensity", kPointUint16), true},
      {"ouster_reflectivity_u8", Retyped(test::OusterCloud(), "reflectivity", kPointUint8), true},
      {"ouster_no_reflectivity", Without(test::OusterCloud(), "reflectivity"), true},
      {"ouster_no_reflectivity_intensity_u16",
       Retyped(Without(test::OusterCloud(), "reflectivity"), "intensity", kPointUint16), true},
      {"ouster_reflectivity_f64", Retyped(test::OusterCloud(), "reflectivity", kPointFloat64), false},
      {"ouster_ring_i32", Retyped(test::OusterCloud(), "ring", kPointInt32), false},
      {"ouster_x_float64", x_f64, false},
      {"velodyne_time_float64", velodyne_f64, false},
      {"hesai", test::HesaiCloud(), false},
      {"livox", test::LivoxCloud(), false},
  };
}

// Random points: most in range, some NaN/Inf, zero (no return), too near or
// too far, times mostly in [lo, hi] (s for float time fields, ns for
// integer ones), some corrupt.
void FillRandom(RawCloud* c, uint32_t width, uint32_t height, uint32_t pad, std::mt19937* rng) {
  c->Resize(width, height, pad);
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const bool seconds = c->time_field == "time" || c->time_field == "timestamp";
  const bool negative = std::uniform_int_distribution<int>(0, 1)(*rng) == 1;
  std::uniform_real_distribution<double> coord(-60.0, 60.0), unit(0.0, 1.0);
  for (uint32_t i = 0; i < width * height; ++i) {
    double x = coord(*rng), y = coord(*rng), z = 0.1 * coord(*rng);
    const double u = unit(*rng);
    if (u < 0.03) x = nan;
    else if (u < 0.05) y = inf;
    else if (u < 0.10) x = y = z = 0.0;
    else if (u < 0.13) x = 0.2, y = z = 0.0;
    else if (u < 0.16) x = 5000.0;
    double t = unit(*rng) * 0.1;  // s
    if (negative && seconds) t -= 0.1;
    if (c->time_field == "timestamp") t += static_cast<double>(kStamp) * 1e-9;
    if (!seconds) t *= 1e9;
    if (unit(*rng) < 0.02 && seconds) t = nan;
    c->SetPoint(i, x, y, z, 1000.0 * unit(*rng), t, static_cast<int>(i % 128));
  }
}

void ExpectSameScan(const Scan& a, const Scan& b, const std::string& where) {
  ASSERT_EQ(a.points.size(), b.points.size()) << where;
  EXPECT_EQ(a.t_start_ns, b.t_start_ns) << where;
  EXPECT_EQ(a.t_end_ns, b.t_end_ns) << where;
  EXPECT_EQ(a.has_intensity, b.has_intensity) << where;
  EXPECT_EQ(a.has_ring, b.has_ring) << where;
  for (size_t i = 0; i < a.points.size(); ++i) {
    const LidarPoint& p = a.points[i];
    const LidarPoint& q = b.points[i];
    ASSERT_EQ(std::memcmp(p.p_lidar.data(), q.p_lidar.data(), 3 * sizeof(float)), 0)
        << where << " point " << i;
    ASSERT_EQ(p.t_ns, q.t_ns) << where << " point " << i;
    ASSERT_EQ(std::memcmp(&p.intensity, &q.intensity, sizeof(float)), 0) << where << " point " << i;
    ASSERT_EQ(p.ring, q.ring) << where << " point " << i;
  }
}

TEST(PointCloud2FastPath, SameScanAsGenericReaderOnEveryLayout) {
  std::mt19937 rng(18);
  for (const Case& c : Cases()) {
    for (const std::string stamp : {"auto", "start", "end"}) {
      for (int trial = 0; trial < 6; ++trial) {
        RawCloud cloud = c.cloud;
        cloud.stamp_ns = kStamp;
        const uint32_t width = 1 + rng() % 300, height = 1 + rng() % 4, pad = rng() % 9;
        FillRandom(&cloud, width, height, pad, &rng);
        LidarOptions lidar;
        lidar.header_stamp = stamp;
        lidar.min_range = 0.5;
        lidar.max_range = 100.0;
        const std::string where = c.name + " stamp=" + stamp + " trial " + std::to_string(trial);
        DecodeStats fast_stats, generic_stats;
        const StatusOr<Scan> fast = DecodePointCloud2(cloud.View(), lidar, &fast_stats);
        const StatusOr<Scan> generic = DecodePointCloud2Generic(cloud.View(), lidar, &generic_stats);
        ASSERT_TRUE(fast.ok()) << where << ": " << fast.status().message();
        ASSERT_TRUE(generic.ok()) << where;
        EXPECT_EQ(fast_stats.fast_path, c.fast) << where;
        EXPECT_FALSE(generic_stats.fast_path) << where;
        EXPECT_EQ(fast_stats.layout, generic_stats.layout) << where;
        EXPECT_EQ(fast_stats.stamp_is_end, generic_stats.stamp_is_end) << where;
        EXPECT_EQ(fast_stats.raw_points, generic_stats.raw_points) << where;
        EXPECT_EQ(fast_stats.invalid_points, generic_stats.invalid_points) << where;
        EXPECT_EQ(fast_stats.out_of_range_points, generic_stats.out_of_range_points) << where;
        EXPECT_GT(fast->points.size(), 0u) << where;  // the comparison covers kept points
        ExpectSameScan(*fast, *generic, where);
      }
    }
  }
}

TEST(PointCloud2FastPath, ErrorsAreTheGenericReadersErrors) {
  RawCloud cloud = test::OusterCloud();
  cloud.stamp_ns = kStamp;
  std::mt19937 rng(3);
  FillRandom(&cloud, 50, 1, 0, &rng);
  PointCloud2View view = cloud.View();
  view.data_size -= 1;  // one byte short
  LidarOptions lidar;
  const StatusOr<Scan> fast = DecodePointCloud2(view, lidar);
  const StatusOr<Scan> generic = DecodePointCloud2Generic(view, lidar);
  ASSERT_FALSE(fast.ok());
  ASSERT_FALSE(generic.ok());
  EXPECT_EQ(fast.status().message(), generic.status().message());
}

// Rows are walked one by one: a cloud of zero-width rows must not visit its
// (up to 2^32) empty rows. Found by the fuzzer.
TEST(PointCloud2FastPath, ZeroWidthCloudWithHugeHeightIsEmpty) {
  RawCloud cloud = test::OusterCloud();
  cloud.stamp_ns = kStamp;
  PointCloud2View view = cloud.View();
  view.height = std::numeric_limits<uint32_t>::max();
  view.width = 0;
  view.row_step = 0;
  LidarOptions lidar;
  for (const bool fast : {true, false}) {
    DecodeStats stats;
    const StatusOr<Scan> scan =
        fast ? DecodePointCloud2(view, lidar, &stats) : DecodePointCloud2Generic(view, lidar, &stats);
    ASSERT_TRUE(scan.ok()) << scan.status().message();
    EXPECT_TRUE(scan->points.empty());
    EXPECT_EQ(stats.raw_points, 0);
    EXPECT_EQ(scan->t_start_ns, kStamp);
  }
}

}  // namespace
}  // namespace rvlio

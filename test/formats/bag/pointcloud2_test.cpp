// DecodePointCloud2: layouts, stamp handling, dropping and validation.
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "cloud_builder.h"
#include "rvlio/formats/pointcloud2.h"

namespace rvlio {
namespace {

using test::RawCloud;

constexpr TimeNs kCloudStamp = 1700000000123456789LL;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Expected {
  float x, y, z;
  int ring;
};

// Point i of a deterministic pattern: ranges 2..5 m, rings 0..15.
Expected PatternPoint(uint32_t i, uint32_t n) {
  const double a = 2.0 * M_PI * i / n;
  const double r = 2.0 + 0.5 * (i % 7);
  return {float(r * std::cos(a)), float(r * std::sin(a)), float(0.1 * (i % 5) - 0.2),
          int(i % 16)};
}

LidarOptions Lidar(const std::string& type = "auto", const std::string& stamp = "auto") {
  LidarOptions o;
  o.type = type;
  o.header_stamp = stamp;
  o.min_range = 0.5;
  o.max_range = 100.0;
  return o;
}

// Fills n pattern points with time value time_of(i) in the cloud's time field.
template <typename F>
void FillPattern(RawCloud* c, uint32_t n, F time_of) {
  c->Resize(n);
  for (uint32_t i = 0; i < n; ++i) {
    const Expected e = PatternPoint(i, n);
    c->SetPoint(i, e.x, e.y, e.z, 10.0 + i, time_of(i), e.ring);
  }
}

void ExpectPattern(const Scan& scan, uint32_t n, bool check_ring = true) {
  ASSERT_EQ(scan.points.size(), n);
  for (uint32_t i = 0; i < n; ++i) {
    const Expected e = PatternPoint(i, n);
    EXPECT_EQ(scan.points[i].p_lidar.x(), e.x) << i;
    EXPECT_EQ(scan.points[i].p_lidar.y(), e.y) << i;
    EXPECT_EQ(scan.points[i].p_lidar.z(), e.z) << i;
    if (check_ring) {
      EXPECT_EQ(scan.points[i].ring, e.ring) << i;
    }
  }
}

// Ouster gives reflectivity (calibrated) and intensity (signal): the
// reflectivity is the point's intensity; a layout without either has none,
// which the scan says (the map then has no intensity field, not zeros).
TEST(PointCloud2Decode, ReflectivityBeforeIntensityAndTheScanSaysWhatItHas) {
  RawCloud c = test::OusterCloud();
  c.stamp_ns = kCloudStamp;
  FillPattern(&c, 20, [](uint32_t i) { return 500.0 * i; });
  for (uint32_t i = 0; i < 20; ++i) c.Set(i, "intensity", 1000.0 + i);  // signal photons
  for (const bool fast : {true, false}) {
    StatusOr<Scan> scan = fast ? DecodePointCloud2(c.View(), Lidar())
                               : DecodePointCloud2Generic(c.View(), Lidar());
    ASSERT_TRUE(scan.ok()) << scan.status().message();
    EXPECT_TRUE(scan->has_intensity && scan->has_ring);
    for (uint32_t i = 0; i < 20; ++i) EXPECT_EQ(scan->points[i].intensity, 10.0f + i) << i;
  }
  RawCloud bare = test::VelodyneCloud();
  bare.fields.erase(bare.fields.begin() + 3);  // intensity
  bare.fields.erase(bare.fields.begin() + 3);  // ring
  bare.ring_field.clear();
  bare.stamp_ns = kCloudStamp;
  FillPattern(&bare, 20, [](uint32_t i) { return 1e-4 * i; });
  StatusOr<Scan> scan = DecodePointCloud2(bare.View(), Lidar());
  ASSERT_TRUE(scan.ok()) << scan.status().message();
  EXPECT_FALSE(scan->has_intensity);
  EXPECT_FALSE(scan->has_ring);
}

TEST(PointCloud2Decode, OusterRelativeNsFromStartStamp) {
  RawCloud c = test::OusterCloud();
  c.stamp_ns = kCloudStamp;
  const uint32_t n = 200;
  FillPattern(&c, n, [](uint32_t i) { return 500.0 * i + 7; });
  DecodeStats stats;
  StatusOr<Scan> scan = DecodePointCloud2(c.View(), Lidar(), &stats);
  ASSERT_TRUE(scan.ok()) << scan.status().message();
  ExpectPattern(*scan, n);
  for (uint32_t i = 0; i < n; ++i) {
    EXPECT_EQ(scan->points[i].t_ns, kCloudStamp + 500 * i + 7);
    EXPECT_FLOAT_EQ(scan->points[i].intensity, 10.0f + i);
  }
  EXPECT_EQ(scan->t_start_ns, kCloudStamp + 7);
  EXPECT_EQ(scan->t_end_ns, kCloudStamp + 500 * (n - 1) + 7);
  EXPECT_EQ(stats.layout, "ouster");
  EXPECT_FALSE(stats.stamp_is_end);
  EXPECT_EQ(stats.raw_points, n);
  EXPECT_EQ(stats.invalid_points, 0);
}

TEST(PointCloud2Decode, OusterForcedEndStampPutsLastPointAtStamp) {
  RawCloud c = test::OusterCloud();
  c.stamp_ns = kCloudStamp;
  const uint32_t n = 64;
  FillPattern(&c, n, [](uint32_t i) { return 1000.0 * i; });
  DecodeStats stats;
  StatusOr<Scan> scan = DecodePointCloud2(c.View(), Lidar("ouster", "end"), &stats);
  ASSERT_TRUE(scan.ok()) << scan.status().message();
  EXPECT_TRUE(stats.stamp_is_end);
  EXPECT_EQ(scan->t_end_ns, kCloudStamp);
  EXPECT_EQ(scan->t_start_ns, kCloudStamp - 1000 * (n - 1));
  for (uint32_t i = 0; i < n; ++i)
    EXPECT_EQ(scan->points[i].t_ns, kCloudStamp - 1000 * TimeNs(n - 1) + 1000 * TimeNs(i));
}

TimeNs RelSecondsToNs(double s) { return std::llround(double(float(s)) * 1e9); }

TEST(PointCloud2Decode, VelodyneNegativeTimesMeanEndStamp) {
  RawCloud c = test::VelodyneCloud();
  c.stamp_ns = kCloudStamp;
  const uint32_t n = 100;
  auto rel = [](uint32_t i) { return -0.099 + 0.001 * i; };  // -0.099 .. 0
  FillPattern(&c, n, rel);
  for (const std::string stamp : {"auto", "end"}) {
    DecodeStats stats;
    StatusOr<Scan> scan = DecodePointCloud2(c.View(), Lidar("auto", stamp), &stats);
    ASSERT_TRUE(scan.ok()) << scan.status().message();
    EXPECT_EQ(stats.layout, "velodyne");
    EXPECT_TRUE(stats.stamp_is_end) << stamp;
    ExpectPattern(*scan, n);
    for (uint32_t i = 0; i < n; ++i)
      EXPECT_EQ(scan->points[i].t_ns, kCloudStamp + RelSecondsToNs(rel(i))) << stamp << " " << i;
    EXPECT_LE(std::llabs(scan->t_end_ns - kCloudStamp), 1);
  }
}

TEST(PointCloud2Decode, VelodynePositiveTimesMeanStartStamp) {
  RawCloud c = test::VelodyneCloud();
  c.stamp_ns = kCloudStamp;
  const uint32_t n = 100;
  auto rel = [](uint32_t i) { return 0.001 * i; };
  FillPattern(&c, n, rel);
  DecodeStats stats;
  StatusOr<Scan> scan = DecodePointCloud2(c.View(), Lidar(), &stats);
  ASSERT_TRUE(scan.ok()) << scan.status().message();
  EXPECT_FALSE(stats.stamp_is_end);
  EXPECT_EQ(scan->t_start_ns, kCloudStamp);
  for (uint32_t i = 0; i < n; ++i) EXPECT_EQ(scan->points[i].t_ns, kCloudStamp + RelSecondsToNs(rel(i)));
}

TEST(PointCloud2Decode, VelodyneForcedStartWithNegativeTimesPutsFirstPointAtStamp) {
  RawCloud c = test::VelodyneCloud();
  c.stamp_ns = kCloudStamp;
  const uint32_t n = 50;
  auto rel = [](uint32_t i) { return -0.05 + 0.001 * i; };
  FillPattern(&c, n, rel);
  DecodeStats stats;
  StatusOr<Scan> scan = DecodePointCloud2(c.View(), Lidar("velodyne", "start"), &stats);
  ASSERT_TRUE(scan.ok()) << scan.status().message();
  EXPECT_FALSE(stats.stamp_is_end);
  EXPECT_EQ(scan->t_start_ns, kCloudStamp);
  for (uint32_t i = 0; i < n; ++i) {
    const double shifted = double(float(rel(i))) * 1e9 - double(float(rel(0))) * 1e9;
    EXPECT_EQ(scan->points[i].t_ns, kCloudStamp + std::llround(shifted));
  }
}

TEST(PointCloud2Decode, HesaiAbsoluteSecondsAndStampDetection) {
  RawCloud c = test::HesaiCloud();
  const uint32_t n = 120;
  const double t0 = 1700000000.25;
  auto abs_s = [&](uint32_t i) { return t0 + 1e-4 * i; };
  FillPattern(&c, n, abs_s);
  for (bool end : {false, true}) {
    c.stamp_ns = end ? SecondsToNs(abs_s(n - 1)) : SecondsToNs(t0);
    DecodeStats stats;
    StatusOr<Scan> scan = DecodePointCloud2(c.View(), Lidar(), &stats);
    ASSERT_TRUE(scan.ok()) << scan.status().message();
    EXPECT_EQ(stats.layout, "hesai");
    EXPECT_EQ(stats.stamp_is_end, end);
    ExpectPattern(*scan, n);
    // A float64 of ~1.7e9 s resolves ~0.24 us.
    for (uint32_t i = 0; i < n; ++i)
      EXPECT_NEAR(double(scan->points[i].t_ns - 1700000000LL * kNsPerSecond),
                  0.25e9 + 1e5 * i, 300.0);
  }
}

TEST(PointCloud2Decode, LivoxAbsoluteTimestampInNanosecondsOrSeconds) {
  const uint32_t n = 80;
  const TimeNs t0 = 1700000000500000000LL;
  for (bool ns_unit : {true, false}) {
    RawCloud c = test::LivoxCloud();
    c.stamp_ns = t0;
    FillPattern(&c, n, [&](uint32_t i) {
      const TimeNs t = t0 + 250000 * TimeNs(i);
      return ns_unit ? double(t) : double(t) * 1e-9;
    });
    DecodeStats stats;
    StatusOr<Scan> scan = DecodePointCloud2(c.View(), Lidar(), &stats);
    ASSERT_TRUE(scan.ok()) << scan.status().message();
    EXPECT_EQ(stats.layout, "livox");
    EXPECT_FALSE(stats.stamp_is_end);
    ExpectPattern(*scan, n);  // ring from `line`
    for (uint32_t i = 0; i < n; ++i)
      EXPECT_NEAR(double(scan->points[i].t_ns - t0), 250000.0 * i, 600.0) << ns_unit << " " << i;
  }
}

TEST(PointCloud2Decode, LivoxOffsetTimeIsRelativeNs) {
  RawCloud c = test::LivoxOffsetCloud();
  c.stamp_ns = kCloudStamp;
  const uint32_t n = 30;
  FillPattern(&c, n, [](uint32_t i) { return 3333.0 * i; });
  DecodeStats stats;
  StatusOr<Scan> scan = DecodePointCloud2(c.View(), Lidar(), &stats);
  ASSERT_TRUE(scan.ok()) << scan.status().message();
  EXPECT_EQ(stats.layout, "livox");
  ExpectPattern(*scan, n);
  for (uint32_t i = 0; i < n; ++i) EXPECT_EQ(scan->points[i].t_ns, kCloudStamp + 3333 * i);
}

TEST(PointCloud2Decode, ForcedTypeOverridesDetectionAndNeedsItsField) {
  RawCloud c = test::HesaiCloud();
  c.stamp_ns = kCloudStamp;
  FillPattern(&c, 10, [](uint32_t i) { return 1700000000.0 + 0.01 * i; });
  // hesai fields read as livox: still absolute seconds (nearest the stamp).
  DecodeStats stats;
  StatusOr<Scan> scan = DecodePointCloud2(c.View(), Lidar("livox"), &stats);
  ASSERT_TRUE(scan.ok()) << scan.status().message();
  EXPECT_EQ(stats.layout, "livox");
  EXPECT_NEAR(double(scan->points[9].t_ns - scan->points[0].t_ns), 0.09e9, 1000.0);

  StatusOr<Scan> bad = DecodePointCloud2(c.View("/hesai"), Lidar("ouster"));
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(bad.status().message().find("no field 't' required by lidar.type=ouster"),
            std::string::npos) << bad.status().message();
  EXPECT_NE(bad.status().message().find("/hesai"), std::string::npos);

  StatusOr<Scan> unknown = DecodePointCloud2(c.View(), Lidar("sick"));
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.status().message().find("sick"), std::string::npos);
}

TEST(PointCloud2Decode, NoTimeFieldSaysWhatToDo) {
  RawCloud c = test::MakeCloud({{"x", 0, kPointFloat32, 1}, {"y", 4, kPointFloat32, 1},
                                {"z", 8, kPointFloat32, 1}, {"intensity", 12, kPointFloat32, 1}},
                               16, "", "");
  c.Resize(4);
  StatusOr<Scan> scan = DecodePointCloud2(c.View("/x"), Lidar());
  ASSERT_FALSE(scan.ok());
  EXPECT_EQ(scan.status().message(),
            "PointCloud2 on /x has no per-point time field; fields are x,y,z,intensity; set "
            "lidar.type or use a driver that stamps points");
  StatusOr<std::string> layout = DetectPointCloud2Layout(c.View(), "auto");
  EXPECT_FALSE(layout.ok());
}

TEST(PointCloud2Decode, OrganizedCloudDropsNoReturnNanInfAndOutOfRange) {
  RawCloud c = test::OusterCloud();
  c.stamp_ns = kCloudStamp;
  const uint32_t rows = 4, cols = 8;
  c.Resize(cols, rows, /*pad=*/12);
  int expect_invalid = 0, expect_range = 0, expect_kept = 0;
  for (uint32_t i = 0; i < rows * cols; ++i) {
    const double t = 1000.0 * (i % cols);
    switch (i % 8) {
      case 0: c.SetPoint(i, 0, 0, 0, 0, t, i / cols); ++expect_invalid; break;  // no return
      case 1: c.SetPoint(i, kNaN, 1, 1, 0, t, i / cols); ++expect_invalid; break;
      case 2: c.SetPoint(i, 1, std::numeric_limits<double>::infinity(), 1, 0, t, i / cols);
              ++expect_invalid; break;
      case 3: c.SetPoint(i, 0.1, 0.1, 0.0, 0, t, i / cols); ++expect_range; break;  // < 0.5 m
      case 4: c.SetPoint(i, 150.0, 0.0, 0.0, 0, t, i / cols); ++expect_range; break;  // > 100 m
      default: c.SetPoint(i, 3.0 + i, -1.0, 0.5, 0, t, i / cols); ++expect_kept; break;
    }
  }
  DecodeStats stats;
  StatusOr<Scan> scan = DecodePointCloud2(c.View(), Lidar(), &stats);
  ASSERT_TRUE(scan.ok()) << scan.status().message();
  EXPECT_EQ(int(scan->points.size()), expect_kept);
  EXPECT_EQ(stats.invalid_points, expect_invalid);
  EXPECT_EQ(stats.out_of_range_points, expect_range);
  EXPECT_EQ(stats.raw_points, rows * cols);
  for (const LidarPoint& p : scan->points) {
    const uint32_t i = uint32_t(std::lround(p.p_lidar.x() - 3.0));
    EXPECT_EQ(p.ring, i / cols);
    EXPECT_EQ(p.t_ns, kCloudStamp + 1000 * TimeNs(i % cols));
    EXPECT_FLOAT_EQ(p.p_lidar.y(), -1.0f);
  }
  // A cloud with only dropped points decodes to an empty scan at the stamp.
  RawCloud empty = test::OusterCloud();
  empty.stamp_ns = kCloudStamp;
  empty.Resize(5, 2);
  StatusOr<Scan> none = DecodePointCloud2(empty.View(), Lidar(), &stats);
  ASSERT_TRUE(none.ok());
  EXPECT_TRUE(none->points.empty());
  EXPECT_EQ(none->t_start_ns, kCloudStamp);
  EXPECT_EQ(stats.invalid_points, 10);
}

TEST(PointCloud2Decode, BigEndianCloudDecodesLikeLittleEndian) {
  for (RawCloud base : {test::OusterCloud(), test::VelodyneCloud(), test::HesaiCloud()}) {
    RawCloud big = base;
    big.is_bigendian = true;
    const std::string field = base.time_field;
    auto time_of = [&](uint32_t i) {
      return field == "timestamp" ? 1700000000.0 + 1e-3 * i : field == "time" ? 1e-3 * i : 100.0 * i;
    };
    base.stamp_ns = big.stamp_ns = kCloudStamp;
    FillPattern(&base, 40, time_of);
    FillPattern(&big, 40, time_of);
    ASSERT_NE(base.data, big.data);
    StatusOr<Scan> a = DecodePointCloud2(base.View(), Lidar());
    StatusOr<Scan> b = DecodePointCloud2(big.View(), Lidar());
    ASSERT_TRUE(a.ok() && b.ok());
    ASSERT_EQ(a->points.size(), 40u);
    ASSERT_EQ(b->points.size(), 40u);
    for (size_t i = 0; i < 40; ++i) {
      EXPECT_EQ(a->points[i].p_lidar, b->points[i].p_lidar);
      EXPECT_EQ(a->points[i].t_ns, b->points[i].t_ns);
      EXPECT_EQ(a->points[i].ring, b->points[i].ring);
    }
  }
}

// --- validation -----------------------------------------------------------

void ExpectRejected(const RawCloud& c, const std::string& needle) {
  StatusOr<Scan> scan = DecodePointCloud2(c.View("/v"), Lidar());
  ASSERT_FALSE(scan.ok()) << "expected: " << needle;
  EXPECT_EQ(scan.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(scan.status().message().find(needle), std::string::npos) << scan.status().message();
}

RawCloud SmallOuster() {
  RawCloud c = test::OusterCloud();
  c.stamp_ns = kCloudStamp;
  FillPattern(&c, 10, [](uint32_t i) { return 10.0 * i; });
  return c;
}

TEST(PointCloud2Validate, FieldOutsidePointStep) {
  RawCloud c = SmallOuster();
  c.fields[4].offset = 46;  // t: 4 bytes at 46 > 48
  ExpectRejected(c, "field 't' (offset 46, 4 bytes) does not fit in point_step 48");
  c = SmallOuster();
  c.fields[0].count = 0xFFFFFFFFu;  // 4 * count overflows 32 bits
  ExpectRejected(c, "field 'x'");
  c = SmallOuster();
  c.fields[1].offset = 0xFFFFFFFEu;
  ExpectRejected(c, "field 'y'");
}

TEST(PointCloud2Validate, UnknownDatatype) {
  RawCloud c = SmallOuster();
  c.fields[3].datatype = 9;
  ExpectRejected(c, "field 'intensity' has unknown datatype 9");
  c.fields[3].datatype = 0;
  ExpectRejected(c, "unknown datatype 0");
}

TEST(PointCloud2Validate, StridesAndDataSize) {
  RawCloud c = SmallOuster();
  c.row_step = 48 * 10 - 1;
  ExpectRejected(c, "row_step 479 is smaller than point_step * width = 480");
  c = SmallOuster();
  c.data.resize(c.data.size() - 1);
  ExpectRejected(c, "data has 479 bytes, row_step * height needs 480");
  c = SmallOuster();
  c.width = c.height = 0xFFFFFFFFu;  // 2^64 points: no overflow, just rejected
  c.row_step = 0xFFFFFFFFu;
  ExpectRejected(c, "row_step");
  c = SmallOuster();
  c.height = 0x10000u;
  c.row_step = 0x10000u;
  c.width = 10;
  ExpectRejected(c, "data has 480 bytes");
  c = SmallOuster();
  c.fields.clear();
  c.point_step = 0;
  c.row_step = 0;
  ExpectRejected(c, "point_step is 0");
  c = SmallOuster();
  c.fields.erase(c.fields.begin() + 1);  // no y
  ExpectRejected(c, "no x, y, z fields");
}

// Random clouds and random corruptions: the decoder either rejects the
// message or returns points that obey every promise, and never reads outside
// the buffer (the buffer is an exact-size heap block; run under
// RVLIO_SANITIZE=ON to make an overread fatal).
TEST(PointCloud2Fuzz, RandomCorruptionsAreRejectedOrDecodedConsistently) {
  std::mt19937 rng(12345);
  auto uni = [&](uint32_t lo, uint32_t hi) {
    return std::uniform_int_distribution<uint32_t>(lo, hi)(rng);
  };
  const std::vector<RawCloud> bases = {test::OusterCloud(), test::VelodyneCloud(),
                                       test::HesaiCloud(), test::LivoxCloud(),
                                       test::LivoxOffsetCloud()};
  int accepted = 0, rejected = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    RawCloud c = bases[trial % bases.size()];
    c.stamp_ns = kCloudStamp;
    const bool abs = c.time_field == "timestamp";
    FillPattern(&c, uni(0, 40), [&](uint32_t i) { return abs ? 1.7e9 + 1e-3 * i : 1e3 * i; });
    const int mutations = int(uni(0, 3));
    for (int m = 0; m < mutations; ++m) {
      switch (uni(0, 9)) {
        case 0: c.point_step = uni(0, 64); break;
        case 1: c.row_step = uni(0, 2000); break;
        case 2: c.width = uni(0, 100); break;
        case 3: c.height = uni(0, 5); break;
        case 4: c.fields[uni(0, uint32_t(c.fields.size()) - 1)].offset = uni(0, 80); break;
        case 5: c.fields[uni(0, uint32_t(c.fields.size()) - 1)].datatype = uint8_t(uni(0, 10)); break;
        case 6: c.fields[uni(0, uint32_t(c.fields.size()) - 1)].count = uni(0, 3); break;
        case 7: c.data.resize(uni(0, uint32_t(c.data.size()) + 10)); break;
        case 8: for (auto& b : c.data) if (uni(0, 9) == 0) b = uint8_t(uni(0, 255)); break;
        default: c.is_bigendian = !c.is_bigendian; break;
      }
    }
    // Exact-size copy so that any overread leaves the allocation.
    std::unique_ptr<uint8_t[]> exact(new uint8_t[c.data.size() + (c.data.empty() ? 1 : 0)]);
    std::copy(c.data.begin(), c.data.end(), exact.get());
    PointCloud2View view = c.View();
    view.data = c.data.empty() ? nullptr : exact.get();
    DecodeStats stats;
    LidarOptions lidar = Lidar();
    StatusOr<Scan> scan = DecodePointCloud2(view, lidar, &stats);
    if (!scan.ok()) {
      ++rejected;
      EXPECT_EQ(scan.status().code(), StatusCode::kInvalidInput);
      EXPECT_FALSE(scan.status().message().empty());
      continue;
    }
    ++accepted;
    if (stats.raw_points > 0) {
      EXPECT_LE(uint64_t(c.row_step) * c.height, c.data.size());
    }
    EXPECT_EQ(stats.raw_points, int64_t(uint64_t(c.width) * c.height));
    EXPECT_EQ(int64_t(scan->points.size()) + stats.invalid_points + stats.out_of_range_points,
              stats.raw_points);
    for (const LidarPoint& p : scan->points) {
      ASSERT_TRUE(p.p_lidar.allFinite());
      const double r = p.p_lidar.cast<double>().norm();
      EXPECT_GE(r, lidar.min_range * (1 - 1e-6));
      EXPECT_LE(r, lidar.max_range * (1 + 1e-6));
      EXPECT_GE(p.t_ns, scan->t_start_ns);
      EXPECT_LE(p.t_ns, scan->t_end_ns);
    }
  }
  // Both branches must be exercised for the test to mean anything.
  EXPECT_GT(accepted, 500);
  EXPECT_GT(rejected, 500);
}

}  // namespace
}  // namespace rvlio

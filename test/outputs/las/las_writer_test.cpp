// LasWriter (formats/las_writer.h): the bytes of the file against the tables
// of the ASPRS LAS 1.4 R15 specification (public header block, VLR header,
// point data record format 6, Extra Bytes descriptor), read back here with
// plain offsets; millimetres at survey-sized coordinates; GPS time; the file
// appears complete or not at all; memory stays bounded however many points.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "las_test_util.h"
#include "rvlio/formats/las_writer.h"

namespace rvlio {
namespace {

using las_test::At;
using las_test::ReadBytes;
using las_test::ScratchDir;
using las_test::Text;

// One VLR as found by walking the file from the end of the header.
struct FoundVlr {
  std::string user_id, description;
  uint16_t record_id = 0;
  std::string payload;
};

std::vector<FoundVlr> WalkVlrs(const std::string& b) {
  std::vector<FoundVlr> out;
  size_t at = At<uint16_t>(b, 94);
  for (uint32_t i = 0; i < At<uint32_t>(b, 100); ++i) {
    FoundVlr v;
    EXPECT_EQ(At<uint16_t>(b, at), 0) << "reserved";
    v.user_id = Text(b, at + 2, 16);
    v.record_id = At<uint16_t>(b, at + 18);
    const uint16_t length = At<uint16_t>(b, at + 20);
    v.description = Text(b, at + 22, 32);
    v.payload = b.substr(at + 54, length);
    out.push_back(v);
    at += 54 + length;
  }
  EXPECT_EQ(at, At<uint32_t>(b, 96)) << "the VLRs end where the points begin";
  return out;
}

const FoundVlr* Find(const std::vector<FoundVlr>& vlrs, const std::string& user, uint16_t id) {
  for (const FoundVlr& v : vlrs)
    if (v.user_id == user && v.record_id == id) return &v;
  return nullptr;
}
// The result points into `vlrs`: a temporary would leave it dangling.
const FoundVlr* Find(std::vector<FoundVlr>&& vlrs, const std::string& user, uint16_t id) = delete;

TEST(LasWriter, HeaderVlrsAndRecordsFollowTheSpecification) {
  ScratchDir dir;
  LasWriterOptions o;
  o.crs_wkt = "PROJCS[\"test\"]";
  o.extra_fields = {{"deviation_m", LasScalar::kFloat, "to the reference"},
                    {"scan_index", LasScalar::kUint32, ""}};
  o.has_time = true;
  LasWriter w;
  ASSERT_TRUE(w.Open(dir.Path("a.las"), o).ok());
  const double extra[3][2] = {{0.25, 7}, {std::nan(""), 8}, {-0.5, 9}};
  const Eigen::Vector3d p[3] = {{12.3456, -7.5, 1.0}, {1500.0, 20.0, -3.25}, {-2.0, 3.0, 4.0}};
  for (int i = 0; i < 3; ++i) {
    LasPoint q;
    q.p_m = p[i];
    q.unix_time_s = 1.7e9 + i;
    q.extra = extra[i];
    ASSERT_TRUE(w.Write(q).ok());
  }
  ASSERT_TRUE(w.Commit().ok());
  const std::string b = ReadBytes(dir.Path("a.las"));
  EXPECT_EQ(b.substr(0, 4), "LASF");
  EXPECT_EQ(At<uint16_t>(b, 4), 0) << "file source ID";
  EXPECT_EQ(At<uint16_t>(b, 6), 0x11) << "adjusted standard GPS time and WKT";
  EXPECT_EQ(At<uint8_t>(b, 24), 1);
  EXPECT_EQ(At<uint8_t>(b, 25), 4);
  EXPECT_EQ(Text(b, 26, 32), "rvlio lidar-inertial map");
  EXPECT_EQ(Text(b, 58, 32).rfind("rvlio ", 0), 0u);
  EXPECT_GE(At<uint16_t>(b, 92), 2024) << "creation year";
  EXPECT_GE(At<uint16_t>(b, 90), 1) << "creation day";
  EXPECT_EQ(At<uint16_t>(b, 94), 375);
  EXPECT_EQ(At<uint32_t>(b, 100), 3u) << "text, WKT, extra bytes";
  EXPECT_EQ(At<uint8_t>(b, 104), 6);
  EXPECT_EQ(At<uint16_t>(b, 105), 30 + 4 + 4);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(At<uint32_t>(b, 107 + 4 * i), 0u) << "legacy counts";
  for (int i = 0; i < 3; ++i) EXPECT_EQ(At<double>(b, 131 + 8 * i), 0.001);
  EXPECT_EQ(At<double>(b, 155), 0.0) << "the first point rounded down to 1 km";
  EXPECT_EQ(At<double>(b, 163), -1000.0);
  EXPECT_EQ(At<double>(b, 171), 0.0);
  EXPECT_DOUBLE_EQ(At<double>(b, 179), 1500.0);  // max x
  EXPECT_DOUBLE_EQ(At<double>(b, 187), -2.0);    // min x
  EXPECT_DOUBLE_EQ(At<double>(b, 195), 20.0);
  EXPECT_DOUBLE_EQ(At<double>(b, 203), -7.5);
  EXPECT_DOUBLE_EQ(At<double>(b, 211), 4.0);
  EXPECT_DOUBLE_EQ(At<double>(b, 219), -3.25);
  EXPECT_EQ(At<uint64_t>(b, 227), 0u) << "waveform";
  EXPECT_EQ(At<uint64_t>(b, 235), 0u) << "EVLR start";
  EXPECT_EQ(At<uint32_t>(b, 243), 0u) << "EVLR count";
  EXPECT_EQ(At<uint64_t>(b, 247), 3u);
  EXPECT_EQ(At<uint64_t>(b, 255), 3u) << "first returns";
  for (int i = 1; i < 15; ++i) EXPECT_EQ(At<uint64_t>(b, 255 + 8 * i), 0u);
  const uint32_t start = At<uint32_t>(b, 96);
  EXPECT_EQ(b.size(), start + 3 * 38u);

  const std::vector<FoundVlr> vlrs = WalkVlrs(b);
  const FoundVlr* wkt = Find(vlrs, "LASF_Projection", 2112);
  ASSERT_NE(wkt, nullptr);
  EXPECT_EQ(wkt->payload, o.crs_wkt + std::string(1, '\0')) << "null-terminated";
  const FoundVlr* text = Find(vlrs, "LASF_Spec", 3);
  ASSERT_NE(text, nullptr);
  EXPECT_NE(text->payload.find("Adjusted Standard GPS Time"), std::string::npos) << text->payload;
  const FoundVlr* eb = Find(vlrs, "LASF_Spec", 4);
  ASSERT_NE(eb, nullptr);
  ASSERT_EQ(eb->payload.size(), 2 * 192u);
  const std::string& d = eb->payload;
  EXPECT_EQ(At<uint8_t>(d, 2), 9) << "float";
  EXPECT_EQ(At<uint8_t>(d, 3), 0x7) << "no_data, min, max";
  EXPECT_EQ(Text(d, 4, 32), "deviation_m");
  EXPECT_TRUE(std::isnan(At<double>(d, 40))) << "no_data NaN";
  EXPECT_EQ(At<double>(d, 64), -0.5) << "min of the finite values";
  EXPECT_EQ(At<double>(d, 88), 0.25);
  EXPECT_EQ(Text(d, 160, 32), "to the reference");
  EXPECT_EQ(At<uint8_t>(d, 192 + 2), 5) << "unsigned long";
  EXPECT_EQ(At<uint8_t>(d, 192 + 3), 0x6) << "min and max, no no_data";
  EXPECT_EQ(At<uint64_t>(d, 192 + 64), 7u);
  EXPECT_EQ(At<uint64_t>(d, 192 + 88), 9u);

  for (int i = 0; i < 3; ++i) {
    const size_t r = start + 38 * i;
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(At<int32_t>(b, r + 4 * k) * 0.001 + At<double>(b, 155 + 8 * k), p[i][k], 5e-4);
    EXPECT_EQ(At<uint16_t>(b, r + 12), 0) << "no intensity";
    EXPECT_EQ(At<uint8_t>(b, r + 14), 0x11) << "return 1 of 1";
    EXPECT_EQ(At<uint8_t>(b, r + 15), 0);
    EXPECT_EQ(At<uint8_t>(b, r + 16), 0) << "classification";
    EXPECT_EQ(At<int16_t>(b, r + 18), 0) << "scan angle";
    EXPECT_EQ(At<uint16_t>(b, r + 20), 0) << "point source ID";
    EXPECT_DOUBLE_EQ(At<double>(b, r + 22), 1.7e9 + i - 315964800.0 + 18 - 1e9);
    const float dev = At<float>(b, r + 30);
    if (std::isnan(extra[i][0])) EXPECT_TRUE(std::isnan(dev));
    else EXPECT_EQ(dev, static_cast<float>(extra[i][0]));
    EXPECT_EQ(At<uint32_t>(b, r + 34), static_cast<uint32_t>(extra[i][1]));
  }
}

TEST(LasWriter, SurveySizedCoordinatesKeepTheirMillimetres) {
  ScratchDir dir;
  LasWriter w;
  ASSERT_TRUE(w.Open(dir.Path("survey.las"), {}).ok());
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < 1000; ++i)  // easting 500 000, northing 5 400 000, every mm different
    p.emplace_back(500000.0 + 0.001 * i + 0.0004, 5400000.0 + 0.37 * i + 0.0003, 312.123 + 0.011 * i);
  for (const auto& q : p) {
    LasPoint lp;
    lp.p_m = q;
    ASSERT_TRUE(w.Write(lp).ok());
  }
  ASSERT_TRUE(w.Commit().ok());
  const std::string b = ReadBytes(dir.Path("survey.las"));
  EXPECT_EQ(At<double>(b, 155), 500000.0);
  EXPECT_EQ(At<double>(b, 163), 5400000.0);
  const uint32_t start = At<uint32_t>(b, 96);
  for (size_t i = 0; i < p.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const double back = At<int32_t>(b, start + 30 * i + 4 * k) * 0.001 + At<double>(b, 155 + 8 * k);
      ASSERT_NEAR(back, p[i][k], 0.0005 + 1e-9) << i << " " << k;
      // The stored value is the input rounded to the millimetre of the CRS.
      ASSERT_NEAR(back, std::round(p[i][k] * 1000.0) / 1000.0, 1e-9) << i << " " << k;
    }
  EXPECT_NEAR(At<double>(b, 179), 500000.999, 1e-9) << "max x: the stored maximum";
  EXPECT_NEAR(At<double>(b, 187), 500000.000, 1e-9) << "min x";
  EXPECT_NEAR(At<double>(b, 195), 5400369.63, 1e-9);
  EXPECT_NEAR(At<double>(b, 203), 5400000.000, 1e-9);
}

TEST(LasWriter, GpsTimeIsUnixTimePlusLeapSecondsMinusTheGpsEpochAndOneBillion) {
  // 2023-11-14 22:13:20 UTC: 18 leap seconds.
  EXPECT_DOUBLE_EQ(UnixToAdjustedGpsTime(1.7e9), 1.7e9 - 315964800.0 + 18.0 - 1e9);
  // 2001-09-09 01:46:40 UTC: 13 leap seconds (the 1999-01-01 one is the last before).
  EXPECT_DOUBLE_EQ(UnixToAdjustedGpsTime(1e9), 1e9 - 315964800.0 + 13.0 - 1e9);
  // Across the leap second of 2016-12-31 (UNIX 1483228800 = 2017-01-01).
  EXPECT_DOUBLE_EQ(UnixToAdjustedGpsTime(1483228799.5) + 0.5 + 1.0,
                   UnixToAdjustedGpsTime(1483228800.0));
  // The GPS epoch itself.
  EXPECT_DOUBLE_EQ(UnixToAdjustedGpsTime(315964800.0), -1e9);
}

TEST(LasWriter, IntensityRingScanIndexAndIntegerExtrasAreScaledClampedAndCounted) {
  ScratchDir dir;
  LasWriterOptions o;
  o.intensity_scale = 256.0;  // an 8-bit sensor
  o.intensity_source = "intensity";
  o.has_ring = true;
  o.has_point_source = true;
  o.extra_fields = {{"code", LasScalar::kInt16, ""}};
  LasWriter w;
  ASSERT_TRUE(w.Open(dir.Path("i.las"), o).ok());
  const double intensity[] = {0.0, 255.0, 300.0, -4.0, std::nan("")};
  const int ring[] = {0, 127, 255, 300, -1};
  const double code[] = {-5.4, 40000.0, -40000.0, 3.5, 0.0};
  const uint64_t scan_index[] = {0, 65535, 65536, 70000, 3};
  for (int i = 0; i < 5; ++i) {
    LasPoint q;
    q.p_m = Eigen::Vector3d(i, 0, 0);
    q.intensity = intensity[i];
    q.ring = ring[i];
    q.scan_index = scan_index[i];
    q.extra = &code[i];
    ASSERT_TRUE(w.Write(q).ok());
  }
  ASSERT_TRUE(w.Commit().ok());
  EXPECT_EQ(w.stats().intensity_clamped, 3u);
  EXPECT_EQ(w.stats().ring_saturated, 2u);
  const std::string b = ReadBytes(dir.Path("i.las"));
  const uint32_t start = At<uint32_t>(b, 96);
  const uint16_t want_intensity[] = {0, 65280, 65535, 0, 0};
  const uint8_t want_ring[] = {0, 127, 255, 255, 0};
  const int16_t want_code[] = {-5, 32767, -32768, 4, 0};
  const uint16_t want_source[] = {0, 65535, 0, 4464, 3};  // modulo 65536
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(At<uint16_t>(b, start + 32 * i + 20), want_source[i]) << i;
    EXPECT_EQ(At<uint16_t>(b, start + 32 * i + 12), want_intensity[i]) << i;
    EXPECT_EQ(At<uint8_t>(b, start + 32 * i + 17), want_ring[i]) << i;
    EXPECT_EQ(At<int16_t>(b, start + 32 * i + 30), want_code[i]) << i;
    EXPECT_EQ(At<double>(b, start + 32 * i + 22), 0.0) << "no time given";
  }
  const std::vector<FoundVlr> vlrs = WalkVlrs(b);  // Find points into it
  const FoundVlr* text = Find(vlrs, "LASF_Spec", 3);
  ASSERT_NE(text, nullptr);
  EXPECT_NE(text->payload.find("Point source ID: the scan index modulo 65536"), std::string::npos)
      << text->payload;
}

TEST(LasWriter, EmptyMapIsAValidFileWithoutPoints) {
  ScratchDir dir;
  LasWriter w;
  ASSERT_TRUE(w.Open(dir.Path("empty.las"), {}).ok());
  ASSERT_TRUE(w.Commit().ok());
  const std::string b = ReadBytes(dir.Path("empty.las"));
  EXPECT_EQ(At<uint64_t>(b, 247), 0u);
  EXPECT_EQ(b.size(), At<uint32_t>(b, 96));
  for (int i = 0; i < 6; ++i) EXPECT_EQ(At<double>(b, 179 + 8 * i), 0.0);
}

TEST(LasWriter, APointBeyondTheIntegerRangeOrNotFiniteLeavesNoFile) {
  ScratchDir dir;
  LasWriterOptions o;
  o.offset_m = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& bad : {Eigen::Vector3d(2147484.0, 0, 0),
                                     Eigen::Vector3d(0, std::nan(""), 0)}) {
    LasWriter w;
    ASSERT_TRUE(w.Open(dir.Path("far.las"), o).ok());
    LasPoint q;
    ASSERT_TRUE(w.Write(q).ok());
    q.p_m = bad;
    const Status s = w.Write(q);
    EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
    EXPECT_NE(s.message().find("far.las: point 1"), std::string::npos) << s.message();
    EXPECT_EQ(s.message().find('\n'), std::string::npos);
    EXPECT_TRUE(dir.Files().empty()) << dir.Files().front();
  }
  // Just inside the range is written.
  LasWriter w;
  ASSERT_TRUE(w.Open(dir.Path("edge.las"), o).ok());
  LasPoint q;
  q.p_m = Eigen::Vector3d(2147483.0, -2147483.0, 0.0);
  ASSERT_TRUE(w.Write(q).ok());
  ASSERT_TRUE(w.Commit().ok());
}

TEST(LasWriter, BadOptionsAndAnUnwritableFolderAreRefusedBeforeAnythingIsWritten) {
  ScratchDir dir;
  LasWriterOptions o;
  o.extra_fields = {{"a", LasScalar::kFloat, ""}, {"a", LasScalar::kFloat, ""}};
  LasWriter w;
  EXPECT_EQ(w.Open(dir.Path("x.las"), o).code(), StatusCode::kInvalidInput);
  o.extra_fields = {{std::string(33, 'n'), LasScalar::kFloat, ""}};
  EXPECT_EQ(w.Open(dir.Path("x.las"), o).code(), StatusCode::kInvalidInput);
  o.extra_fields.clear();
  o.offset_m = Eigen::Vector3d(0.0005, 0, 0);
  EXPECT_EQ(w.Open(dir.Path("x.las"), o).code(), StatusCode::kInvalidInput);
  EXPECT_TRUE(dir.Files().empty());
  const Status s = w.Open(dir.Path("no/such/folder/x.las"), {});
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find("no/such/folder/x.las"), std::string::npos) << s.message();
}

TEST(LasWriter, ADestroyedWriterLeavesNeitherTheFileNorItsTemporary) {
  ScratchDir dir;
  {
    LasWriter w;
    ASSERT_TRUE(w.Open(dir.Path("gone.las"), {}).ok());
    LasPoint q;
    for (int i = 0; i < 100000; ++i) ASSERT_TRUE(w.Write(q).ok());
  }
  EXPECT_TRUE(dir.Files().empty());
}

TEST(LasWriter, MemoryStaysBoundedWhileMillionsOfPointsAreWritten) {
  ScratchDir dir;
  if (!las_test::ResetPeakRss()) GTEST_SKIP() << "the kernel does not reset the peak RSS";
  const long before_kb = las_test::PeakRssKb();
  LasWriterOptions o;
  o.extra_fields = {{"deviation_m", LasScalar::kFloat, ""}};
  LasWriter w;
  ASSERT_TRUE(w.Open(dir.Path("big.las"), o).ok());
  const double dev = 0.01;
  LasPoint q;
  q.extra = &dev;
  const int n = 4'000'000;  // 136 MB of records
  for (int i = 0; i < n; ++i) {
    q.p_m = Eigen::Vector3d(0.001 * i, 0.5 * (i % 1000), 2.0);
    ASSERT_TRUE(w.Write(q).ok());
  }
  ASSERT_TRUE(w.Commit().ok());
  const long grown_kb = las_test::PeakRssKb() - before_kb;
  EXPECT_LT(grown_kb, 16 * 1024) << "the writer holds the points instead of streaming them";
  std::ifstream in(dir.Path("big.las"), std::ios::binary);
  std::string head(375, '\0');
  in.read(head.data(), 375);
  EXPECT_EQ(At<uint64_t>(head, 247), static_cast<uint64_t>(n));
  EXPECT_EQ(std::filesystem::file_size(dir.Path("big.las")), At<uint32_t>(head, 96) + 34ull * n);
}

}  // namespace
}  // namespace rvlio

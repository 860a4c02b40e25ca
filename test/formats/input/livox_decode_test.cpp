// Livox CustomMsg: ROS1 wire format, decoding (times, filtering, point_num)
// and the ROS1 bag round trip through SensorBagWriter / SensorBagReader.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>

#include <gtest/gtest.h>

#include "cli/cli_util.h"
#include "rvlio/formats/livox.h"
#include "rvlio/formats/pointcloud2.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio {
namespace {

constexpr TimeNs kBase = 1700000000123456789;

LivoxCustomMsg SampleMsg() {
  LivoxCustomMsg msg;
  msg.header_stamp_ns = kBase;
  msg.frame_id = "livox_frame";
  msg.timebase = static_cast<uint64_t>(kBase);
  msg.lidar_id = 3;
  msg.rsvd = {7, 8, 9};
  const float nan = std::numeric_limits<float>::quiet_NaN();
  // kept, kept, NaN, no-return zero, too close (< 0.5 m), too far (> 100 m), kept
  const float xs[] = {2.0f, -3.0f, nan, 0.0f, 0.1f, 150.0f, 1.0f};
  for (int i = 0; i < 7; ++i) {
    LivoxCustomPoint p;
    p.offset_time = static_cast<uint32_t>(1000 * i + 5);
    p.x = xs[i];
    p.y = i == 6 ? 1.0f : 0.0f;
    p.z = 0.0f;
    p.reflectivity = static_cast<uint8_t>(10 + i);
    p.tag = 0x10;
    p.line = static_cast<uint8_t>(i % 6);
    msg.points.push_back(p);
  }
  msg.point_num = 7;
  return msg;
}

TEST(LivoxWire, RoundTripKeepsEveryField) {
  const LivoxCustomMsg msg = SampleMsg();
  const std::vector<uint8_t> bytes = SerializeLivoxRos1(msg);
  // Header 4+8+4+11, timebase 8, point_num 4, lidar_id 1, rsvd 3, count 4, 7 x 19.
  EXPECT_EQ(bytes.size(), 27u + 8 + 4 + 1 + 3 + 4 + 7 * 19);
  StatusOr<LivoxCustomMsg> back = ParseLivoxRos1(bytes.data(), bytes.size());
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->header_stamp_ns, msg.header_stamp_ns);
  EXPECT_EQ(back->frame_id, msg.frame_id);
  EXPECT_EQ(back->timebase, msg.timebase);
  EXPECT_EQ(back->point_num, msg.point_num);
  EXPECT_EQ(back->lidar_id, 3);
  EXPECT_EQ(back->rsvd, msg.rsvd);
  ASSERT_EQ(back->points.size(), msg.points.size());
  for (size_t i = 0; i < msg.points.size(); ++i) {
    EXPECT_EQ(std::memcmp(&back->points[i].x, &msg.points[i].x, 4), 0);  // NaN too
    EXPECT_EQ(back->points[i].offset_time, msg.points[i].offset_time);
    EXPECT_EQ(back->points[i].reflectivity, msg.points[i].reflectivity);
    EXPECT_EQ(back->points[i].tag, msg.points[i].tag);
    EXPECT_EQ(back->points[i].line, msg.points[i].line);
  }
}

TEST(LivoxWire, LittleEndianPackedLayout) {
  LivoxCustomMsg msg;
  msg.header_stamp_ns = 5 * kNsPerSecond + 6;
  msg.frame_id = "f";
  msg.timebase = 0x0102030405060708ull;
  msg.point_num = 1;
  msg.points.push_back({0x0A0B0C0D, 1.0f, 0.0f, 0.0f, 1, 2, 3});
  const std::vector<uint8_t> b = SerializeLivoxRos1(msg);
  ASSERT_EQ(b.size(), 17u + 8 + 4 + 4 + 4 + 19);
  EXPECT_EQ(b[4], 5);   // stamp.sec
  EXPECT_EQ(b[8], 6);   // stamp.nsec
  EXPECT_EQ(b[12], 1);  // frame_id length
  EXPECT_EQ(b[16], 'f');
  EXPECT_EQ(b[17], 0x08);  // timebase, little endian
  EXPECT_EQ(b[24], 0x01);
  EXPECT_EQ(b[25], 1);  // point_num
  EXPECT_EQ(b[33], 1);  // points count
  EXPECT_EQ(b[37], 0x0D);  // offset_time
  EXPECT_EQ(b[53], 1);  // reflectivity
  EXPECT_EQ(b[55], 3);  // line
}

TEST(LivoxWire, ShortLongAndTrailingPayloadsAreRejected) {
  const std::vector<uint8_t> bytes = SerializeLivoxRos1(SampleMsg());
  for (size_t cut : {size_t{0}, size_t{10}, size_t{40}, bytes.size() - 1}) {
    StatusOr<LivoxCustomMsg> r = ParseLivoxRos1(bytes.data(), cut, "/livox/lidar");
    ASSERT_FALSE(r.ok()) << cut;
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidInput);
    EXPECT_NE(r.status().message().find("/livox/lidar"), std::string::npos);
  }
  std::vector<uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_FALSE(ParseLivoxRos1(longer.data(), longer.size()).ok());
  // A huge point count must not allocate or read past the end.
  std::vector<uint8_t> huge = bytes;
  const size_t count_at = 27 + 8 + 4 + 1 + 3;
  std::memset(huge.data() + count_at, 0xFF, 4);
  EXPECT_FALSE(ParseLivoxRos1(huge.data(), huge.size()).ok());
}

TEST(LivoxDecode, TimesAreTimebasePlusOffsetAndInvalidPointsAreCounted) {
  LidarOptions lidar;  // 0.5 .. 100 m
  DecodeStats stats;
  StatusOr<Scan> scan = DecodeLivoxCustomMsg(SampleMsg(), lidar, &stats);
  ASSERT_TRUE(scan.ok()) << scan.status().message();
  EXPECT_EQ(stats.layout, "livox_custom");
  EXPECT_EQ(stats.raw_points, 7);
  EXPECT_EQ(stats.invalid_points, 2);       // NaN, zero
  EXPECT_EQ(stats.out_of_range_points, 2);  // 0.1 m, 150 m
  ASSERT_EQ(scan->points.size(), 3u);
  EXPECT_EQ(scan->points[0].t_ns, kBase + 5);
  EXPECT_EQ(scan->points[1].t_ns, kBase + 1005);
  EXPECT_EQ(scan->points[2].t_ns, kBase + 6005);
  EXPECT_EQ(scan->t_start_ns, kBase + 5);
  EXPECT_EQ(scan->t_end_ns, kBase + 6005);
  EXPECT_FLOAT_EQ(scan->points[1].p_lidar.x(), -3.0f);
  EXPECT_FLOAT_EQ(scan->points[1].intensity, 11.0f);
  EXPECT_EQ(scan->points[1].ring, 1);
}

// The same points as an Ouster PointCloud2 are filtered and counted alike
// (one filter, formats/pointcloud2.h FilterPoint).
TEST(LivoxDecode, FiltersExactlyLikePointCloud2) {
  const LivoxCustomMsg msg = SampleMsg();
  std::vector<uint8_t> data(msg.points.size() * 16);
  for (size_t i = 0; i < msg.points.size(); ++i) {
    const auto& p = msg.points[i];
    std::memcpy(&data[i * 16 + 0], &p.x, 4);
    std::memcpy(&data[i * 16 + 4], &p.y, 4);
    std::memcpy(&data[i * 16 + 8], &p.z, 4);
    std::memcpy(&data[i * 16 + 12], &p.offset_time, 4);
  }
  PointCloud2View cloud;
  cloud.header_stamp_ns = kBase;
  cloud.height = 1;
  cloud.width = static_cast<uint32_t>(msg.points.size());
  cloud.point_step = 16;
  cloud.row_step = 16 * cloud.width;
  cloud.fields = {{"x", 0, kPointFloat32, 1}, {"y", 4, kPointFloat32, 1},
                  {"z", 8, kPointFloat32, 1}, {"t", 12, kPointUint32, 1}};
  cloud.data = data.data();
  cloud.data_size = data.size();
  DecodeStats pc_stats, lx_stats;
  StatusOr<Scan> pc = DecodePointCloud2(cloud, LidarOptions(), &pc_stats);
  StatusOr<Scan> lx = DecodeLivoxCustomMsg(msg, LidarOptions(), &lx_stats);
  ASSERT_TRUE(pc.ok() && lx.ok());
  EXPECT_EQ(pc_stats.invalid_points, lx_stats.invalid_points);
  EXPECT_EQ(pc_stats.out_of_range_points, lx_stats.out_of_range_points);
  ASSERT_EQ(pc->points.size(), lx->points.size());
  for (size_t i = 0; i < pc->points.size(); ++i) {
    EXPECT_EQ(pc->points[i].t_ns, lx->points[i].t_ns);
    EXPECT_EQ(pc->points[i].p_lidar, lx->points[i].p_lidar);
  }
}

TEST(LivoxDecode, PointNumMismatchIsInvalidInput) {
  LivoxCustomMsg msg = SampleMsg();
  msg.point_num = 8;
  StatusOr<Scan> scan = DecodeLivoxCustomMsg(msg, LidarOptions());
  ASSERT_FALSE(scan.ok());
  EXPECT_EQ(scan.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(scan.status().message().find("point_num 8"), std::string::npos)
      << scan.status().message();
  EXPECT_NE(scan.status().message().find("7 points"), std::string::npos);
}

TEST(LivoxDecode, OtherLayoutTypesAndAbsurdTimebaseAreRejected) {
  LidarOptions ouster;
  ouster.type = "ouster";
  EXPECT_FALSE(DecodeLivoxCustomMsg(SampleMsg(), ouster).ok());
  LidarOptions livox;
  livox.type = "livox";
  EXPECT_TRUE(DecodeLivoxCustomMsg(SampleMsg(), livox).ok());
  LivoxCustomMsg msg = SampleMsg();
  msg.timebase = std::numeric_limits<uint64_t>::max();
  EXPECT_FALSE(DecodeLivoxCustomMsg(msg, LidarOptions()).ok());
}

TEST(LivoxDecode, ScanToMessageKeepsTimesAndPoints) {
  Scan scan;
  scan.t_start_ns = kBase;
  scan.t_end_ns = kBase + 99000000;
  for (int i = 0; i < 4; ++i) {
    LidarPoint p;
    p.p_lidar = Eigen::Vector3f(1.0f + i, 2.0f, -1.0f);
    p.t_ns = kBase + i * 33000000;
    p.intensity = 40.4f;
    p.ring = static_cast<uint16_t>(i);
    scan.points.push_back(p);
  }
  const LivoxCustomMsg msg = ScanToLivoxCustomMsg(scan, "f");
  EXPECT_EQ(msg.point_num, 4u);
  EXPECT_EQ(msg.timebase, static_cast<uint64_t>(kBase));
  EXPECT_EQ(msg.header_stamp_ns, kBase);
  EXPECT_EQ(msg.points[3].offset_time, 99000000u);
  EXPECT_EQ(msg.points[2].reflectivity, 40);
  StatusOr<Scan> back = DecodeLivoxCustomMsg(msg, LidarOptions());
  ASSERT_TRUE(back.ok());
  ASSERT_EQ(back->points.size(), 4u);
  EXPECT_EQ(back->t_start_ns, scan.t_start_ns);
  EXPECT_EQ(back->t_end_ns, scan.t_end_ns);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(back->points[i].t_ns, scan.points[i].t_ns);
    EXPECT_EQ(back->points[i].p_lidar, scan.points[i].p_lidar);
    EXPECT_EQ(back->points[i].ring, i);
  }
}

TEST(LivoxDecode, DriverMd5AndDefinition) {
  EXPECT_STREQ(kLivoxRos1Type, "livox_ros_driver/CustomMsg");
  EXPECT_STREQ(kLivoxRos2Type, "livox_ros_driver2/msg/CustomMsg");
  EXPECT_STREQ(kLivoxRos1Md5, "e4d6829bdfe657cb6c21a746c86b21a6");
  const std::string def = kLivoxRos1Definition;
  EXPECT_NE(def.find("\nMSG: std_msgs/Header\n"), std::string::npos);
  EXPECT_NE(def.find("\nMSG: livox_ros_driver/CustomPoint\n"), std::string::npos);
  EXPECT_NE(def.find("uint32 offset_time"), std::string::npos);
}

// Written by SensorBagWriter::WriteLivoxScan, read back by the ROS1 reader.
TEST(LivoxBag, WriterAndReaderRoundTrip) {
  const std::string dir = testing_cli::MakeTempDir("rvlio_livox");
  ASSERT_FALSE(dir.empty());
  const std::string path = dir + "/lx.bag";
  Scan scan;
  scan.t_start_ns = kBase;
  scan.t_end_ns = kBase + 50000000;
  for (int i = 0; i < 6; ++i) {
    LidarPoint p;
    p.p_lidar = Eigen::Vector3f(3.0f, float(i), 1.0f);
    p.t_ns = kBase + i * 10000000;
    scan.points.push_back(p);
  }
  scan.points[2].p_lidar.setZero();  // a no-return
  {
    auto writer = SensorBagWriter::Create(path);
    ASSERT_TRUE(writer.ok());
    for (int k = 0; k < 3; ++k) {
      ImuSample imu;
      imu.t_ns = kBase - 5000000 + k * 40000000;
      imu.acc_imu = Eigen::Vector3d(0, 0, 9.8);
      ASSERT_TRUE((*writer)->WriteImu("/imu/data", "imu", imu).ok());
    }
    ASSERT_TRUE((*writer)->WriteLivoxScan("/livox/lidar", "livox_frame", scan).ok());
    ASSERT_TRUE((*writer)->Close().ok());
  }
  LidarOptions lidar;
  lidar.topic = "/livox/lidar";
  ImuOptions imu;
  auto reader = SensorBagReader::Open(path, lidar, imu);
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  EXPECT_EQ((*reader)->lidar_layout(), "livox_custom");
  ImuSample s;
  Scan got;
  int imus = 0, scans = 0;
  for (;;) {
    StatusOr<SensorMessage> m = (*reader)->Next(&s, &got);
    ASSERT_TRUE(m.ok()) << m.status().message();
    if (*m == SensorMessage::kEnd) break;
    if (*m == SensorMessage::kImu) ++imus;
    if (*m == SensorMessage::kScan) {
      ++scans;
      ASSERT_EQ(got.points.size(), 5u);
      EXPECT_EQ(got.t_start_ns, kBase);
      EXPECT_EQ(got.t_end_ns, kBase + 50000000);
      EXPECT_EQ(got.points[2].t_ns, kBase + 30000000);
    }
  }
  EXPECT_EQ(imus, 3);
  EXPECT_EQ(scans, 1);
  EXPECT_EQ((*reader)->stats().invalid_points, 1);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rvlio

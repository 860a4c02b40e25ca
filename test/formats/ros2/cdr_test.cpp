// CDR codec: little-endian round trips through the encoders, big-endian
// payloads built byte by byte (with their alignment padding), and corrupt
// payloads that must fail with a message naming the field.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/formats/cdr.h"

namespace rvlio {
namespace {

using Bytes = std::vector<uint8_t>;

// Appends `value` big endian.
template <typename T>
void PutBe(Bytes* b, T value) {
  uint8_t raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  for (size_t i = 0; i < sizeof(T); ++i) b->push_back(raw[sizeof(T) - 1 - i]);
}
void Pad(Bytes* b, size_t n) { b->insert(b->end(), n, 0xEE); }  // padding need not be zero
void PutStringBe(Bytes* b, const std::string& s) {
  PutBe<uint32_t>(b, static_cast<uint32_t>(s.size() + 1));
  b->insert(b->end(), s.begin(), s.end());
  b->push_back(0);
}

TEST(CdrTest, StringMatchesTheBytesRos2Writes) {
  // /topic message 0 of test/data/ros2_bags/sqlite3_talker (sqlite3 hex dump).
  const Bytes talker = {0x00, 0x01, 0x00, 0x00, 0x10, 0x00, 0x00, 0x00, 'H', 'e', 'l', 'l',
                        'o', ',', ' ', 'w', 'o', 'r', 'l', 'd', '!', ' ', '0', 0x00};
  EXPECT_EQ(cdr::EncodeString("Hello, world! 0"), talker);
  StatusOr<std::string> text = cdr::DecodeString(talker.data(), talker.size(), "/topic");
  ASSERT_TRUE(text.ok()) << text.status().message();
  EXPECT_EQ(*text, "Hello, world! 0");
}

TEST(CdrTest, ImuEncoderPadsTheHeaderToEightBytes) {
  cdr::ImuMessage m;
  m.header_stamp_ns = 7 * kNsPerSecond + 5;
  m.frame_id = "a";
  m.orientation_xyzw = {0.5, -0.5, 0.25, 1.0};
  const Bytes b = cdr::EncodeImu(m);
  // 4 header + sec 4 + nanosec 4 + len 4 + "a\0" 2 = 18; first double at
  // payload offset 16 (absolute 20): 2 padding bytes at 18 and 19.
  ASSERT_EQ(b.size(), 20u + 37 * 8);
  EXPECT_EQ(Bytes(b.begin(), b.begin() + 4), (Bytes{0x00, 0x01, 0x00, 0x00}));
  EXPECT_EQ(b[4], 7);
  EXPECT_EQ(b[8], 5);
  EXPECT_EQ(b[12], 2);
  EXPECT_EQ(b[16], 'a');
  EXPECT_EQ(b[17], 0);
  EXPECT_EQ(b[18], 0);
  EXPECT_EQ(b[19], 0);
  double x = 0.0;
  std::memcpy(&x, b.data() + 20, 8);
  EXPECT_EQ(x, 0.5);
}

TEST(CdrTest, ImuRoundTripLittleEndian) {
  cdr::ImuMessage m;
  m.header_stamp_ns = 1700000000LL * kNsPerSecond + 123456789;
  m.frame_id = "imu_link";
  m.orientation_xyzw = {0.1, 0.2, 0.3, 0.9};
  for (int i = 0; i < 9; ++i) {
    m.orientation_covariance[i] = i;
    m.angular_velocity_covariance[i] = 10 + i;
    m.linear_acceleration_covariance[i] = 20 + i;
  }
  m.angular_velocity = {0.01, -0.02, 0.03};
  m.linear_acceleration = {0.1, 0.2, 9.81};
  const Bytes b = cdr::EncodeImu(m);
  StatusOr<cdr::ImuMessage> d = cdr::DecodeImu(b.data(), b.size(), "/imu");
  ASSERT_TRUE(d.ok()) << d.status().message();
  EXPECT_EQ(d->header_stamp_ns, m.header_stamp_ns);
  EXPECT_EQ(d->frame_id, m.frame_id);
  EXPECT_EQ(d->orientation_xyzw, m.orientation_xyzw);
  EXPECT_EQ(d->orientation_covariance, m.orientation_covariance);
  EXPECT_EQ(d->angular_velocity, m.angular_velocity);
  EXPECT_EQ(d->angular_velocity_covariance, m.angular_velocity_covariance);
  EXPECT_EQ(d->linear_acceleration, m.linear_acceleration);
  EXPECT_EQ(d->linear_acceleration_covariance, m.linear_acceleration_covariance);
}

TEST(CdrTest, PointCloud2RoundTripLittleEndian) {
  const Bytes data = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
  PointCloud2View v;
  v.header_stamp_ns = 42 * kNsPerSecond + 1;
  v.height = 1;
  v.width = 2;
  v.fields = {{"x", 0, kPointFloat32, 1}, {"t", 4, kPointUint32, 1}};
  v.point_step = 8;
  v.row_step = 16;
  v.data = data.data();
  v.data_size = data.size();
  const Bytes b = cdr::EncodePointCloud2(v, "os_lidar", true);
  StatusOr<PointCloud2View> d = cdr::DecodePointCloud2(b.data(), b.size(), "/points");
  ASSERT_TRUE(d.ok()) << d.status().message();
  EXPECT_EQ(d->header_stamp_ns, v.header_stamp_ns);
  EXPECT_EQ(d->height, 1u);
  EXPECT_EQ(d->width, 2u);
  ASSERT_EQ(d->fields.size(), 2u);
  EXPECT_EQ(d->fields[1].name, "t");
  EXPECT_EQ(d->fields[1].offset, 4u);
  EXPECT_EQ(d->fields[1].datatype, kPointUint32);
  EXPECT_EQ(d->fields[1].count, 1u);
  EXPECT_FALSE(d->is_bigendian);
  EXPECT_EQ(d->point_step, 8u);
  EXPECT_EQ(d->row_step, 16u);
  ASSERT_EQ(d->data_size, data.size());
  EXPECT_EQ(Bytes(d->data, d->data + d->data_size), data);
  EXPECT_EQ(d->topic, "/points");
}

TEST(CdrTest, LivoxCustomMsgRoundTripLittleEndian) {
  LivoxCustomMsg m;
  m.header_stamp_ns = 5 * kNsPerSecond;
  m.frame_id = "livox_frame";
  m.timebase = 5 * kNsPerSecond + 100;
  m.point_num = 2;
  m.lidar_id = 3;
  m.rsvd = {1, 2, 3};
  m.points = {{0, 1.0f, 2.0f, 3.0f, 10, 0, 1}, {1000, -1.0f, 0.5f, 0.25f, 200, 16, 5}};
  const Bytes b = cdr::EncodeLivoxCustomMsg(m);
  StatusOr<LivoxCustomMsg> d = cdr::DecodeLivoxCustomMsg(b.data(), b.size(), "/livox/lidar");
  ASSERT_TRUE(d.ok()) << d.status().message();
  EXPECT_EQ(d->header_stamp_ns, m.header_stamp_ns);
  EXPECT_EQ(d->frame_id, m.frame_id);
  EXPECT_EQ(d->timebase, m.timebase);
  EXPECT_EQ(d->point_num, 2u);
  EXPECT_EQ(d->lidar_id, 3);
  EXPECT_EQ(d->rsvd, m.rsvd);
  ASSERT_EQ(d->points.size(), 2u);
  EXPECT_EQ(d->points[1].offset_time, 1000u);
  EXPECT_EQ(d->points[1].x, -1.0f);
  EXPECT_EQ(d->points[1].z, 0.25f);
  EXPECT_EQ(d->points[1].reflectivity, 200);
  EXPECT_EQ(d->points[1].tag, 16);
  EXPECT_EQ(d->points[1].line, 5);
}

// sensor_msgs/msg/Imu, big endian, frame "ab": 13 bytes of header fields +
// 3 padding bytes before the first float64 (payload offset 16).
Bytes BigEndianImu() {
  Bytes b = {0x00, 0x00, 0x00, 0x00};
  PutBe<int32_t>(&b, 100);
  PutBe<uint32_t>(&b, 250);
  PutStringBe(&b, "ab");  // payload offsets 8..14
  Pad(&b, 1);             // 15 -> 16
  const double values[37] = {0.0, 0.0, 0.0, 1.0};
  for (int i = 0; i < 37; ++i) {
    double v = values[i];
    if (i >= 13 && i < 16) v = i - 12.0;       // angular_velocity 1 2 3
    if (i >= 25 && i < 28) v = 10.0 * (i - 24);  // linear_acceleration 10 20 30
    PutBe<double>(&b, v);
  }
  return b;
}

TEST(CdrTest, ImuBigEndianWithAlignmentPadding) {
  const Bytes b = BigEndianImu();
  ASSERT_EQ(b.size(), 4u + 16 + 37 * 8);
  EXPECT_EQ(b[4 + 15], 0xEE);  // the padding byte sits where XCDR1 puts it
  StatusOr<cdr::ImuMessage> d = cdr::DecodeImu(b.data(), b.size(), "/imu");
  ASSERT_TRUE(d.ok()) << d.status().message();
  EXPECT_EQ(d->header_stamp_ns, 100 * kNsPerSecond + 250);
  EXPECT_EQ(d->frame_id, "ab");
  EXPECT_EQ(d->orientation_xyzw[3], 1.0);
  EXPECT_EQ(d->angular_velocity, (std::array<double, 3>{1.0, 2.0, 3.0}));
  EXPECT_EQ(d->linear_acceleration, (std::array<double, 3>{10.0, 20.0, 30.0}));
}

TEST(CdrTest, PointCloud2BigEndianWithAlignmentPadding) {
  Bytes b = {0x00, 0x00, 0x00, 0x00};
  PutBe<int32_t>(&b, 3);
  PutBe<uint32_t>(&b, 9);
  PutStringBe(&b, "");       // frame_id: offsets 8..12
  Pad(&b, 3);                // 13 -> 16
  PutBe<uint32_t>(&b, 1);    // height
  PutBe<uint32_t>(&b, 2);    // width
  PutBe<uint32_t>(&b, 2);    // fields: 2
  PutStringBe(&b, "x");      // 28..33
  Pad(&b, 2);                // 34 -> 36
  PutBe<uint32_t>(&b, 0);    // offset
  b.push_back(kPointFloat32);  // datatype at 40
  Pad(&b, 3);                // 41 -> 44
  PutBe<uint32_t>(&b, 1);    // count
  PutStringBe(&b, "time");   // 48..56
  Pad(&b, 3);                // 57 -> 60
  PutBe<uint32_t>(&b, 4);
  b.push_back(kPointFloat32);  // 64
  Pad(&b, 3);
  PutBe<uint32_t>(&b, 1);    // 68
  b.push_back(1);            // is_bigendian at 72
  Pad(&b, 3);
  PutBe<uint32_t>(&b, 8);    // point_step at 76
  PutBe<uint32_t>(&b, 16);   // row_step at 80
  PutBe<uint32_t>(&b, 16);   // data count at 84
  for (float f : {1.0f, 0.0f, 2.0f, 0.05f}) PutBe<float>(&b, f);
  b.push_back(1);            // is_dense
  StatusOr<PointCloud2View> d = cdr::DecodePointCloud2(b.data(), b.size(), "/velodyne_points");
  ASSERT_TRUE(d.ok()) << d.status().message();
  EXPECT_EQ(d->header_stamp_ns, 3 * kNsPerSecond + 9);
  EXPECT_EQ(d->width, 2u);
  ASSERT_EQ(d->fields.size(), 2u);
  EXPECT_EQ(d->fields[0].name, "x");
  EXPECT_EQ(d->fields[1].name, "time");
  EXPECT_EQ(d->fields[1].offset, 4u);
  EXPECT_EQ(d->fields[1].datatype, kPointFloat32);
  EXPECT_TRUE(d->is_bigendian);
  EXPECT_EQ(d->point_step, 8u);
  EXPECT_EQ(d->row_step, 16u);
  EXPECT_EQ(d->data_size, 16u);
  EXPECT_EQ(d->data, b.data() + 4 + 88);
}

TEST(CdrTest, SequenceLongerThanTheBufferIsRejectedNamingTheField) {
  Bytes b = BigEndianImu();
  b.resize(4 + 16);
  Bytes cloud = {0x00, 0x01, 0x00, 0x00};
  for (int i = 0; i < 4; ++i) cloud.push_back(0);  // sec
  for (int i = 0; i < 4; ++i) cloud.push_back(0);  // nanosec
  cloud.insert(cloud.end(), {1, 0, 0, 0, 0});      // frame_id ""
  cloud.insert(cloud.end(), 3, 0);
  cloud.insert(cloud.end(), 8, 0);                 // height, width
  cloud.insert(cloud.end(), {0xff, 0xff, 0xff, 0x7f});  // fields: 2^31 - 1 elements
  StatusOr<PointCloud2View> d = cdr::DecodePointCloud2(cloud.data(), cloud.size(), "/points");
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(d.status().message().find("'fields'"), std::string::npos) << d.status().message();
  EXPECT_NE(d.status().message().find("2147483647"), std::string::npos) << d.status().message();
  EXPECT_NE(d.status().message().find("/points"), std::string::npos) << d.status().message();

  // The data byte sequence claims more bytes than are left.
  PointCloud2View v;
  const Bytes data(64, 1);
  v.data = data.data();
  v.data_size = data.size();
  Bytes ok = cdr::EncodePointCloud2(v, "f", false);
  ok.resize(ok.size() - 10);
  d = cdr::DecodePointCloud2(ok.data(), ok.size(), "/points");
  ASSERT_FALSE(d.ok());
  EXPECT_NE(d.status().message().find("'data'"), std::string::npos) << d.status().message();

  StatusOr<cdr::ImuMessage> imu = cdr::DecodeImu(b.data(), b.size(), "/imu");
  ASSERT_FALSE(imu.ok());
  EXPECT_NE(imu.status().message().find("orientation"), std::string::npos);
}

TEST(CdrTest, BadEncapsulationAndTruncationAreErrors) {
  Bytes b = cdr::EncodeString("hi");
  b[1] = 0x02;  // PL_CDR_BE: parameter lists are not plain CDR
  StatusOr<std::string> s = cdr::DecodeString(b.data(), b.size(), "");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("encapsulation"), std::string::npos);
  const Bytes short_payload = {0x00};
  EXPECT_FALSE(cdr::DecodeString(short_payload.data(), short_payload.size(), "").ok());
  EXPECT_FALSE(cdr::DecodeString(nullptr, 0, "").ok());
  Bytes unterminated = cdr::EncodeString("hi");
  unterminated.back() = 'x';
  s = cdr::DecodeString(unterminated.data(), unterminated.size(), "");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("NUL"), std::string::npos);
  // Every prefix of a valid message fails cleanly.
  cdr::ImuMessage m;
  m.frame_id = "imu";
  const Bytes imu = cdr::EncodeImu(m);
  for (size_t n = 0; n < imu.size(); ++n)
    EXPECT_FALSE(cdr::DecodeImu(imu.data(), n, "/imu").ok()) << n;
}

// The outputs of `rvlio live` (nav_messages.h): byte layout of a TFMessage
// (sequence count, then per transform a header whose strings realign the
// doubles to 8) and round trips of Odometry and TFMessage.
TEST(CdrTest, TfMessageLayoutAlignsDoublesAfterStrings) {
  TransformMessage t;
  t.stamp_ns = 1500000000;  // 1 s + 0.5 s
  t.frame_id = "odom";
  t.child_frame_id = "base";
  t.translation = {1.0, 2.0, 3.0};
  const std::vector<uint8_t> b = cdr::EncodeTfMessage({t});
  // encapsulation 4 | count 4 | sec 4, nanosec 4 | "odom" + NUL: length 4 + 5, pad 3 |
  // "base" + NUL: 4 + 5, pad to 8: 7 | 7 doubles 56
  ASSERT_EQ(b.size(), 4u + 4 + 8 + 12 + 16 + 56);
  EXPECT_EQ(b[4], 1);  // one transform
  EXPECT_EQ(b[8], 1);  // sec = 1
  EXPECT_EQ(b[16], 5);  // strlen("odom") + 1
  double x = 0.0;
  std::memcpy(&x, b.data() + 4 + 4 + 8 + 12 + 16, 8);
  EXPECT_EQ(x, 1.0);
  StatusOr<std::vector<TransformMessage>> back = cdr::DecodeTfMessage(b.data(), b.size(), "/tf");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ASSERT_EQ(back->size(), 1u);
  EXPECT_EQ((*back)[0].child_frame_id, "base");
  EXPECT_EQ((*back)[0].stamp_ns, t.stamp_ns);
  EXPECT_EQ((*back)[0].translation, t.translation);
  for (size_t n = 0; n < b.size(); ++n)
    EXPECT_FALSE(cdr::DecodeTfMessage(b.data(), n, "/tf").ok()) << n;
}

TEST(CdrTest, OdometryRoundTrip) {
  OdometryMessage m;
  m.stamp_ns = 1234567890123;
  m.frame_id = "odom";
  m.child_frame_id = "base_link";
  m.pose.position = {1.0, -2.0, 0.5};
  m.pose.orientation_xyzw = {0.0, 0.0, std::sqrt(0.5), std::sqrt(0.5)};
  for (int i = 0; i < 36; ++i) m.pose_covariance[i] = 0.01 * i;
  m.linear_velocity = {1.5, 0.0, 0.0};
  m.angular_velocity = {0.0, 0.0, 0.2};
  const std::vector<uint8_t> b = cdr::EncodeOdometry(m);
  StatusOr<OdometryMessage> back = cdr::DecodeOdometry(b.data(), b.size(), "/odometry");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->stamp_ns, m.stamp_ns);
  EXPECT_EQ(back->frame_id, m.frame_id);
  EXPECT_EQ(back->child_frame_id, m.child_frame_id);
  EXPECT_EQ(back->pose.position, m.pose.position);
  EXPECT_EQ(back->pose.orientation_xyzw, m.pose.orientation_xyzw);
  EXPECT_EQ(back->pose_covariance, m.pose_covariance);
  EXPECT_EQ(back->linear_velocity, m.linear_velocity);
  EXPECT_EQ(back->angular_velocity, m.angular_velocity);
  // 4 + header (8 + 4 + 5 -> 17, pad 3) + child (4 + 10 -> 34, pad to 40) + 85 doubles.
  EXPECT_EQ(b.size(), 4u + 40 + 8 * (7 + 36 + 6 + 36));
  EXPECT_FALSE(cdr::DecodeOdometry(b.data(), b.size() - 1, "/odometry").ok());
}

}  // namespace
}  // namespace rvlio

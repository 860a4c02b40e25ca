// The ROS1 wire parsers of sensor_msgs/PointCloud2 and sensor_msgs/Imu
// (src/formats/ros1_messages.h) against the bytes ROS's own serializer writes.
#include <cstring>
#include <vector>

#include <gtest/gtest.h>
#include <ros/message_traits.h>
#include <ros/serialization.h>

#include "../src/formats/ros1_messages.h"
#include "bag_fixture.h"
#include "cloud_builder.h"

namespace rvlio {
namespace {

template <typename Msg>
std::vector<uint8_t> Serialize(const Msg& msg) {
  std::vector<uint8_t> bytes(ros::serialization::serializationLength(msg));
  ros::serialization::OStream stream(bytes.data(), static_cast<uint32_t>(bytes.size()));
  ros::serialization::serialize(stream, msg);
  return bytes;
}

sensor_msgs::PointCloud2 SampleCloud() {
  test::RawCloud c = test::OusterCloud();
  c.stamp_ns = 1700000000123456789LL;
  c.width = 7;
  c.height = 3;
  c.row_step = c.width * c.point_step;
  c.data.resize(size_t{c.row_step} * c.height);
  for (size_t i = 0; i < c.data.size(); ++i) c.data[i] = static_cast<uint8_t>(i * 31 + 7);
  return test::ToMsg(c, "os_sensor");
}

TEST(Ros1Messages, Md5SumsAreTheOnesRosGives) {
  EXPECT_STREQ(bag_detail::kPointCloud2Md5,
               ros::message_traits::MD5Sum<sensor_msgs::PointCloud2>::value());
  EXPECT_STREQ(bag_detail::kImuMd5, ros::message_traits::MD5Sum<sensor_msgs::Imu>::value());
}

TEST(Ros1Messages, PointCloud2ParsedInPlaceEqualsTheMessage) {
  const sensor_msgs::PointCloud2 msg = SampleCloud();
  const std::vector<uint8_t> bytes = Serialize(msg);
  StatusOr<PointCloud2View> v =
      bag_detail::ParseRos1PointCloud2(bytes.data(), bytes.size(), "/points", "here");
  ASSERT_TRUE(v.ok()) << v.status().message();
  EXPECT_EQ(v->header_stamp_ns, static_cast<TimeNs>(msg.header.stamp.toNSec()));
  EXPECT_EQ(v->height, msg.height);
  EXPECT_EQ(v->width, msg.width);
  EXPECT_EQ(v->point_step, msg.point_step);
  EXPECT_EQ(v->row_step, msg.row_step);
  EXPECT_EQ(v->is_bigendian, msg.is_bigendian != 0);
  EXPECT_EQ(v->topic, "/points");
  ASSERT_EQ(v->fields.size(), msg.fields.size());
  for (size_t i = 0; i < msg.fields.size(); ++i) {
    EXPECT_EQ(v->fields[i].name, msg.fields[i].name);
    EXPECT_EQ(v->fields[i].offset, msg.fields[i].offset);
    EXPECT_EQ(v->fields[i].datatype, msg.fields[i].datatype);
    EXPECT_EQ(v->fields[i].count, msg.fields[i].count);
  }
  ASSERT_EQ(v->data_size, msg.data.size());
  // A view into the message bytes, not a copy.
  EXPECT_GE(v->data, bytes.data());
  EXPECT_LE(v->data + v->data_size, bytes.data() + bytes.size());
  EXPECT_EQ(std::memcmp(v->data, msg.data.data(), msg.data.size()), 0);
}

TEST(Ros1Messages, ImuParsedEqualsTheMessage) {
  sensor_msgs::Imu msg = test::ImuMsg(1700000000987654321LL, 0.25, -0.5, 9.75, 0.125);
  msg.angular_velocity.x = -1.5;
  msg.angular_velocity.y = 2.5;
  msg.orientation.w = 0.5;
  msg.linear_acceleration_covariance[8] = 3.0;
  const std::vector<uint8_t> bytes = Serialize(msg);
  StatusOr<bag_detail::Ros1Imu> imu = bag_detail::ParseRos1Imu(bytes.data(), bytes.size(), "here");
  ASSERT_TRUE(imu.ok()) << imu.status().message();
  EXPECT_EQ(imu->header_stamp_ns, static_cast<TimeNs>(msg.header.stamp.toNSec()));
  EXPECT_EQ(imu->angular_velocity, (std::array<double, 3>{-1.5, 2.5, 0.125}));
  EXPECT_EQ(imu->linear_acceleration, (std::array<double, 3>{0.25, -0.5, 9.75}));
}

// Every cut of the bytes is refused with a message naming where, never read
// past (the sanitizer stage runs this too).
TEST(Ros1Messages, EveryTruncationIsRefusedNamingTheTopic) {
  const std::vector<uint8_t> cloud = Serialize(SampleCloud());
  for (size_t n = 0; n < cloud.size(); n += (n < 200 ? 1 : 97)) {
    const std::vector<uint8_t> cut(cloud.begin(), cloud.begin() + n);
    StatusOr<PointCloud2View> v =
        bag_detail::ParseRos1PointCloud2(cut.data(), cut.size(), "/points", "lidar.topic '/points'");
    ASSERT_FALSE(v.ok()) << n;
    EXPECT_NE(v.status().message().find("lidar.topic '/points'"), std::string::npos);
  }
  const std::vector<uint8_t> imu = Serialize(test::ImuMsg(5, 0, 0, 9.8));
  for (size_t n = 0; n < imu.size(); ++n) {
    const std::vector<uint8_t> cut(imu.begin(), imu.begin() + n);
    EXPECT_FALSE(bag_detail::ParseRos1Imu(cut.data(), cut.size(), "imu").ok()) << n;
  }
}

// A field count larger than the bytes could hold is refused before any
// allocation of that size.
TEST(Ros1Messages, HugeFieldCountIsRefused) {
  std::vector<uint8_t> bytes = Serialize(SampleCloud());
  const size_t count_at = 4 + 8 + 4 + std::strlen("os_sensor") + 8;  // seq, stamp, frame, h, w
  const uint32_t huge = 0xFFFFFFF0u;
  std::memcpy(bytes.data() + count_at, &huge, 4);
  EXPECT_FALSE(bag_detail::ParseRos1PointCloud2(bytes.data(), bytes.size(), "/p", "w").ok());
}

}  // namespace
}  // namespace rvlio

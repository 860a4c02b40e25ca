// `rvlio info` names the chunk compression of ROS1 bags too (read from the
// chunk record headers), for bags written by rosbag_storage itself.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>

#include "cli/cli_util.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio {
namespace {

std::string WriteImuBag(const std::string& path, rosbag::compression::CompressionType type) {
  rosbag::Bag bag;
  bag.open(path, rosbag::bagmode::Write);
  bag.setCompression(type);
  bag.setChunkThreshold(1024);  // several chunks
  for (int i = 0; i < 200; ++i) {
    sensor_msgs::Imu msg;
    msg.header.stamp.fromNSec(1000000000ull + i * 5000000ull);
    msg.linear_acceleration.z = 9.81;
    bag.write("/imu", msg.header.stamp, msg);
  }
  bag.close();
  return path;
}

TEST(Ros1CompressionTest, InfoNamesChunkCompression) {
  const std::string dir = testing_cli::MakeTempDir("rvlio_ros1c");
  ASSERT_FALSE(dir.empty());
  const std::vector<std::pair<rosbag::compression::CompressionType, std::string>> cases = {
      {rosbag::compression::Uncompressed, "none"},
      {rosbag::compression::BZ2, "bz2"},
      {rosbag::compression::LZ4, "lz4"}};
  for (const auto& [type, name] : cases) {
    const std::string path = WriteImuBag(dir + "/" + name + ".bag", type);
    StatusOr<BagInfo> info = ReadBagInfo(path);
    ASSERT_TRUE(info.ok()) << info.status().message();
    EXPECT_EQ(info->storage, "ros1");
    EXPECT_EQ(info->compressions, std::vector<std::string>{name}) << path;
    ASSERT_EQ(info->topics.size(), 1u);
    EXPECT_EQ(info->topics[0].count, 200);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rvlio

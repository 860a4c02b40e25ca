#pragma once
// Private helpers shared by the bag reader, writer and info (src/io only):
// the one place that turns rosbag exceptions and ROS messages into rvlio
// values.
#include <map>
#include <string>

#include <ros/time.h>
#include <rosbag/bag.h>
#include <sensor_msgs/PointCloud2.h>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"
#include "rvlio/io/pointcloud2.h"
#include "sensor_reader_common.h"

namespace rvlio::bag_detail {

inline constexpr const char* kPointCloud2Type = "sensor_msgs/PointCloud2";
inline constexpr const char* kImuType = "sensor_msgs/Imu";

// Opens `path` for reading; InvalidInput naming the path when it is missing,
// not a bag, or truncated.
Status OpenForRead(const std::string& path, rosbag::Bag* bag);

// topic -> message type of every connection in the bag.
std::map<std::string, std::string> TopicTypes(const rosbag::Bag& bag);
// DescribeTopics and RequireTopic: sensor_reader_common.h.

TimeNs ToNs(const ros::Time& t);
// The record time of a message at t_ns: rosbag rejects times below
// ros::TIME_MIN (1 ns), so t <= 0 is clamped to it.
ros::Time RecordTime(TimeNs t_ns);

// A view of a deserialized message (valid while `msg` lives).
PointCloud2View ToView(const sensor_msgs::PointCloud2& msg, const std::string& topic);

}  // namespace rvlio::bag_detail

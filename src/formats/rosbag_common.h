#pragma once
// Private helpers shared by the bag reader, writer and info (src/formats only):
// the one place that turns rosbag exceptions and ROS messages into rvlio
// values.
#include <map>
#include <string>
#include <vector>

#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/message_instance.h>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"
#include "rvlio/formats/pointcloud2.h"
#include "ros1_messages.h"  // kPointCloud2Type, kImuType
#include "sensor_reader_common.h"

namespace rvlio::bag_detail {

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

// The serialized bytes of a bag message of any type at the start of
// *buffer; returns their count. The buffer only grows, so that from message
// to message its memory is reused: no allocation, zero fill or page faults
// for the next cloud (IMU messages in between do not shrink it).
size_t ReadRawMessage(const rosbag::MessageInstance& m, std::vector<uint8_t>* buffer);
inline std::vector<uint8_t> RawMessageBytes(const rosbag::MessageInstance& m) {
  std::vector<uint8_t> bytes;
  bytes.resize(ReadRawMessage(m, &bytes));
  return bytes;
}

}  // namespace rvlio::bag_detail

#include "rosbag_common.h"

#include <sys/stat.h>

#include <exception>

#include <rosbag/view.h>

namespace rvlio::bag_detail {

Status OpenForRead(const std::string& path, rosbag::Bag* bag) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return Status::InvalidInput("bag '" + path + "' does not exist");
  if (!S_ISREG(st.st_mode)) return Status::InvalidInput("bag '" + path + "' is not a regular file");
  try {
    bag->open(path, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    return Status::InvalidInput("'" + path + "' is not a readable ROS1 bag (" + e.what() +
                                "); truncated or not a bag?");
  }
  return Status::Ok();
}

std::map<std::string, std::string> TopicTypes(const rosbag::Bag& bag) {
  std::map<std::string, std::string> topics;
  rosbag::View view(bag);
  for (const rosbag::ConnectionInfo* c : view.getConnections()) topics[c->topic] = c->datatype;
  return topics;
}

TimeNs ToNs(const ros::Time& t) { return static_cast<TimeNs>(t.toNSec()); }

ros::Time RecordTime(TimeNs t_ns) {
  ros::Time t;
  t.fromNSec(static_cast<uint64_t>(t_ns < 1 ? 1 : t_ns));
  return t;
}

PointCloud2View ToView(const sensor_msgs::PointCloud2& msg, const std::string& topic) {
  PointCloud2View v;
  v.header_stamp_ns = ToNs(msg.header.stamp);
  v.height = msg.height;
  v.width = msg.width;
  v.point_step = msg.point_step;
  v.row_step = msg.row_step;
  v.is_bigendian = msg.is_bigendian;
  v.fields.reserve(msg.fields.size());
  for (const auto& f : msg.fields) v.fields.push_back({f.name, f.offset, f.datatype, f.count});
  v.data = msg.data.data();
  v.data_size = msg.data.size();
  v.topic = topic;
  return v;
}

}  // namespace rvlio::bag_detail

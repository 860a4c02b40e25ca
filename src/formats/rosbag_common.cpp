#include "rosbag_common.h"

#include <sys/stat.h>

#include <exception>

#include <ros/serialization.h>
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

size_t ReadRawMessage(const rosbag::MessageInstance& m, std::vector<uint8_t>* buffer) {
  const uint32_t size = m.size();
  if (buffer->size() < size) buffer->resize(size);
  ros::serialization::OStream stream(buffer->data(), size);
  m.write(stream);
  return size;
}

}  // namespace rvlio::bag_detail

// ReadBagInfo: what `rvlio info` prints about a bag.
#include <exception>
#include <limits>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/PointCloud2.h>

#include "rosbag_common.h"
#include "rvlio/io/sensor_bag.h"

namespace rvlio {
namespace {

constexpr int kScansToSample = 5;

// Layout, fields and mean point count from the first few messages.
void DescribeCloudTopic(const rosbag::Bag& bag, BagTopicInfo* info) {
  LidarOptions lidar;  // auto layout and stamp; no range crop: count every valid point
  lidar.min_range = 0.0;
  lidar.max_range = std::numeric_limits<double>::max();
  rosbag::View view(bag, rosbag::TopicQuery(info->topic));
  int64_t points = 0;
  for (const rosbag::MessageInstance& m : view) {
    if (info->scans_sampled >= kScansToSample) break;
    auto msg = m.instantiate<sensor_msgs::PointCloud2>();
    if (!msg) break;
    const PointCloud2View cloud = bag_detail::ToView(*msg, info->topic);
    if (info->fields.empty()) {
      for (const auto& f : cloud.fields) info->fields.push_back(f.name);
    }
    DecodeStats stats;
    StatusOr<Scan> scan = DecodePointCloud2(cloud, lidar, &stats);
    if (!scan.ok()) {
      info->lidar_layout = "unknown";
      info->decode_error = scan.status().message();
      return;
    }
    info->lidar_layout = stats.layout;
    info->header_stamp = stats.stamp_is_end ? "end" : "start";
    points += static_cast<int64_t>(scan->points.size());
    ++info->scans_sampled;
  }
  if (info->scans_sampled > 0) info->points_per_scan = double(points) / info->scans_sampled;
}

BagTopicInfo DescribeTopic(const rosbag::Bag& bag, const std::string& topic,
                           const std::string& type, bool decode_clouds) {
  BagTopicInfo info;
  info.topic = topic;
  info.type = type;
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  info.count = view.size();
  if (info.count > 1) {
    const double span = NsToSeconds(bag_detail::ToNs(view.getEndTime()) -
                                    bag_detail::ToNs(view.getBeginTime()));
    if (span > 0.0) info.rate_hz = double(info.count - 1) / span;
  }
  if (decode_clouds && type == bag_detail::kPointCloud2Type) DescribeCloudTopic(bag, &info);
  return info;
}

StatusOr<BagInfo> Describe(const std::string& path, const rosbag::Bag& bag,
                           const std::string& lidar_topic) {
  const auto topics = bag_detail::TopicTypes(bag);
  if (!lidar_topic.empty()) {
    Status s = bag_detail::RequireTopic(path, topics, lidar_topic, bag_detail::kPointCloud2Type,
                                        "--lidar-topic");
    if (!s.ok()) return s;
  }
  BagInfo info;
  info.path = path;
  rosbag::View all(bag);
  info.messages = all.size();
  if (info.messages > 0) {
    info.start_ns = bag_detail::ToNs(all.getBeginTime());
    info.end_ns = bag_detail::ToNs(all.getEndTime());
    info.start_s = NsToSeconds(info.start_ns);
    info.end_s = NsToSeconds(info.end_ns);
  }
  for (const auto& [topic, type] : topics) {
    const bool decode = lidar_topic.empty() || lidar_topic == topic;
    info.topics.push_back(DescribeTopic(bag, topic, type, decode));
  }
  return info;
}

}  // namespace

StatusOr<BagInfo> ReadBagInfo(const std::string& path, const std::string& lidar_topic) {
  rosbag::Bag bag;
  if (Status s = bag_detail::OpenForRead(path, &bag); !s.ok()) return s;
  try {
    return Describe(path, bag, lidar_topic);
  } catch (const std::exception& e) {
    return Status::InvalidInput("reading bag '" + path + "' failed (" + e.what() +
                                "); truncated or corrupt?");
  }
}

}  // namespace rvlio

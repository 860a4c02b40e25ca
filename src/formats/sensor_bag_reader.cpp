// SensorBagReader over rosbag::Bag + rosbag::View: IMU samples and decoded
// scans of two topics, streamed in bag (record) time order.
#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "ros1_raw_message.h"
#include "ouster_source.h"
#include "ros1_messages.h"
#include "rosbag_common.h"
#include "sensor_reader_common.h"
#include "rvlio/formats/recording.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio {
namespace {


// Reads the first message of the LiDAR topic so that a cloud without a
// usable time field fails at Open, not minutes into a run.
StatusOr<std::string> PeekLayout(const rosbag::Bag& bag, const LidarOptions& lidar) {
  rosbag::View view(bag, rosbag::TopicQuery(lidar.topic));
  for (const rosbag::MessageInstance& m : view) {
    if (m.getMD5Sum() != bag_detail::kPointCloud2Md5) break;
    const std::vector<uint8_t> bytes = bag_detail::RawMessageBytes(m);
    StatusOr<PointCloud2View> cloud = bag_detail::ParseRos1PointCloud2(
        bytes.data(), bytes.size(), lidar.topic, "lidar.topic '" + lidar.topic + "'");
    if (!cloud.ok()) return cloud.status();
    return DetectPointCloud2Layout(*cloud, lidar.type);
  }
  return std::string();
}

// ros::Time of a receive time, clamped to what ros::Time holds (unsigned
// seconds): the bag's records are all in that span.
ros::Time RosTime(TimeNs t_ns) {
  const TimeNs max_ns = static_cast<TimeNs>(std::numeric_limits<uint32_t>::max()) * 1000000000 +
                        999999999;
  return ros::Time().fromNSec(static_cast<uint64_t>(std::clamp<TimeNs>(t_ns, 0, max_ns)));
}

class RosbagSensorReader final : public SensorBagReader {
 public:
  RosbagSensorReader(std::string path, LidarOptions lidar, ImuOptions imu)
      : path_(std::move(path)),
        lidar_(std::move(lidar)),
        imu_(std::move(imu)),
        lidar_where_("lidar.topic '" + lidar_.topic + "' in '" + path_ + "'"),
        imu_where_("imu.topic '" + imu_.topic + "' in '" + path_ + "'"),
        gate_(imu_, lidar_, path_) {}

  Status Init(const std::optional<ReceiveTimeRange>& range) {
    if (Status s = bag_detail::OpenForRead(path_, &bag_); !s.ok()) return s;
    try {
      const auto topics = bag_detail::TopicTypes(bag_);
      const auto lidar_topic = topics.find(lidar_.topic);
      livox_ = lidar_topic != topics.end() && lidar_topic->second == kLivoxRos1Type;
      if (Status s = bag_detail::RequireTopic(path_, topics, lidar_.topic,
                                              livox_ ? kLivoxRos1Type : bag_detail::kPointCloud2Type,
                                              "lidar.topic");
          !s.ok())
        return s;
      if (Status s = bag_detail::RequireTopic(path_, topics, imu_.topic, bag_detail::kImuType,
                                              "imu.topic");
          !s.ok())
        return s;
      StatusOr<std::string> layout =
          livox_ ? StatusOr<std::string>(std::string("livox_custom")) : PeekLayout(bag_, lidar_);
      if (!layout.ok()) return layout.status();
      layout_ = *layout;
      const rosbag::TopicQuery query(std::vector<std::string>{lidar_.topic, imu_.topic});
      view_ = range ? std::make_unique<rosbag::View>(bag_, query, RosTime(range->first_ns),
                                                     RosTime(range->last_ns))
                    : std::make_unique<rosbag::View>(bag_, query);
      it_ = view_->begin();
      // An empty or pre-epoch range: rosbag's clamped View would not be empty.
      if (range && (range->first_ns > range->last_ns || range->last_ns < 0)) it_ = view_->end();
    } catch (const std::exception& e) {
      return ReadError(e);
    }
    return Status::Ok();
  }

  StatusOr<SensorMessage> Next(ImuSample* imu, Scan* scan) override {
    RVLIO_CHECK(imu != nullptr && scan != nullptr);
    if (!error_.ok()) return error_;
    try {
      while (it_ != view_->end()) {
        const rosbag::MessageInstance& m = *it_;
        const bool is_imu = m.getTopic() == imu_.topic;
        StatusOr<bool> got = is_imu ? ReadImu(m, imu) : ReadScan(m, scan);
        ++it_;
        if (!got.ok()) return error_ = got.status();
        if (*got) return is_imu ? SensorMessage::kImu : SensorMessage::kScan;
      }
    } catch (const std::exception& e) {
      return error_ = ReadError(e);
    }
    return SensorMessage::kEnd;
  }

  const SensorReaderStats& stats() const override { return gate_.stats(); }
  std::string lidar_layout() const override { return layout_; }

 private:
  Status ReadError(const std::exception& e) const {
    return Status::InvalidInput("reading bag '" + path_ + "' failed (" + e.what() +
                                "); truncated or corrupt?");
  }

  // True when *out holds a new sample; false when it was dropped.
  StatusOr<bool> ReadImu(const rosbag::MessageInstance& m, ImuSample* out) {
    if (m.getMD5Sum() != bag_detail::kImuMd5)
      return Status::InvalidInput(imu_where_ + " does not hold sensor_msgs/Imu");
    const size_t size = bag_detail::ReadRawMessage(m, &bytes_);
    StatusOr<bag_detail::Ros1Imu> msg = bag_detail::ParseRos1Imu(bytes_.data(), size, imu_where_);
    if (!msg.ok()) return msg.status();
    const auto& a = msg->linear_acceleration;
    const auto& w = msg->angular_velocity;
    return gate_.AcceptImu(msg->header_stamp_ns, Eigen::Vector3d(a[0], a[1], a[2]),
                           Eigen::Vector3d(w[0], w[1], w[2]), out);
  }

  // True when *out holds a scan with points; false for an empty scan.
  StatusOr<bool> ReadScan(const rosbag::MessageInstance& m, Scan* out) {
    DecodeStats decode;
    StatusOr<Scan> scan = livox_ ? DecodeLivox(m, &decode) : DecodeCloud(m, &decode);
    if (!scan.ok()) return scan.status();
    layout_ = decode.layout;
    return gate_.AcceptScan(decode, std::move(scan).value(), out);
  }

  // The cloud parsed in place from the message bytes (bytes_ is reused:
  // no allocation or zero-filled copy per message).
  StatusOr<Scan> DecodeCloud(const rosbag::MessageInstance& m, DecodeStats* decode) {
    if (m.getMD5Sum() != bag_detail::kPointCloud2Md5)
      return Status::InvalidInput(lidar_where_ + " does not hold sensor_msgs/PointCloud2");
    const size_t size = bag_detail::ReadRawMessage(m, &bytes_);
    StatusOr<PointCloud2View> cloud =
        bag_detail::ParseRos1PointCloud2(bytes_.data(), size, lidar_.topic, lidar_where_);
    if (!cloud.ok()) return cloud.status();
    return DecodePointCloud2(*cloud, lidar_, decode);
  }

  // Raw message bytes through the ROS-free parser (formats/livox.h).
  StatusOr<Scan> DecodeLivox(const rosbag::MessageInstance& m, DecodeStats* decode) {
    if (m.getMD5Sum() != kLivoxRos1Md5)
      return Status::InvalidInput(lidar_where_ + " holds " + kLivoxRos1Type + " with md5 " +
                                  m.getMD5Sum() + ", not the driver's " + kLivoxRos1Md5 +
                                  " (a different message layout)");
    const size_t size = bag_detail::ReadRawMessage(m, &bytes_);
    StatusOr<LivoxCustomMsg> msg = ParseLivoxRos1(bytes_.data(), size, lidar_where_);
    if (!msg.ok()) return msg.status();
    StatusOr<Scan> scan = DecodeLivoxCustomMsg(*msg, lidar_, decode);
    if (!scan.ok()) return Status::InvalidInput(lidar_where_ + ": " + scan.status().message());
    return scan;
  }

  std::string path_;
  bool livox_ = false;  // the LiDAR topic holds livox_ros_driver/CustomMsg
  LidarOptions lidar_;
  ImuOptions imu_;
  // "lidar.topic '/x' in 'bag'": names the topic in errors (built once, not per message)
  std::string lidar_where_, imu_where_;
  rosbag::Bag bag_;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator it_;
  std::string layout_;
  std::vector<uint8_t> bytes_;  // holds the current message's bytes; reused
  bag_detail::SensorGate gate_;
  Status error_;
};

}  // namespace

StatusOr<std::unique_ptr<SensorBagReader>> bag_detail::OpenRos1SensorReader(
    const std::string& path, const LidarOptions& lidar, const ImuOptions& imu,
    const std::optional<ReceiveTimeRange>& range) {
  auto reader = std::make_unique<RosbagSensorReader>(path, lidar, imu);
  if (Status s = reader->Init(range); !s.ok()) return s;
  return std::unique_ptr<SensorBagReader>(std::move(reader));
}

}  // namespace rvlio

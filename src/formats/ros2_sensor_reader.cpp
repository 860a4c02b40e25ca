// SensorBagReader over a ROS 2 recording (formats/recording.h): CDR IMU samples
// and scans of two topics in receive-time order, with the same topic checks,
// acceptance rules and statistics as the ROS1 reader (sensor_reader_common).
#include <deque>
#include <map>
#include <memory>

#include "rvlio/formats/cdr.h"
#include "rvlio/formats/livox.h"
#include "rvlio/formats/recording.h"
#include "rvlio/formats/sensor_bag.h"
#include "sensor_reader_common.h"

namespace rvlio::bag_detail {
namespace {

std::map<std::string, std::string> TopicTypes(const RecordingSource& source) {
  std::map<std::string, std::string> topics;
  for (const RecordingTopic& t : source.topics()) topics[t.name] = t.type;
  return topics;
}

int TopicIndex(const RecordingSource& source, const std::string& name) {
  const auto& topics = source.topics();
  for (size_t i = 0; i < topics.size(); ++i) {
    if (topics[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

Status RequireCdr(const RecordingSource& source, int topic, const std::string& key) {
  const RecordingTopic& t = source.topics()[topic];
  if (t.serialization_format == "cdr") return Status::Ok();
  return Status::InvalidInput(key + " '" + t.name + "' in bag '" + source.path() +
                              "' is serialized as '" + t.serialization_format +
                              "'; only cdr is read");
}

class Ros2SensorReader final : public SensorBagReader {
 public:
  Ros2SensorReader(std::string path, LidarOptions lidar, ImuOptions imu)
      : path_(std::move(path)), lidar_(std::move(lidar)), imu_(std::move(imu)), gate_(imu_, lidar_, path_) {}

  // With `range` the layout comes from the first LiDAR message inside it.
  Status Init(const std::optional<ReceiveTimeRange>& range) {
    StatusOr<std::unique_ptr<RecordingSource>> source = RecordingSource::Open(path_);
    if (!source.ok()) return source.status();
    source_ = std::move(source).value();
    if (Status s = RequireTopics(); !s.ok()) return TruncationExplains(s);
    lidar_index_ = TopicIndex(*source_, lidar_.topic);
    imu_index_ = TopicIndex(*source_, imu_.topic);
    if (Status s = RequireCdr(*source_, lidar_index_, "lidar.topic"); !s.ok()) return s;
    if (Status s = RequireCdr(*source_, imu_index_, "imu.topic"); !s.ok()) return s;
    if (Status s = source_->SetTopicFilter({lidar_index_, imu_index_}); !s.ok()) return s;
    if (range)
      if (Status s = source_->SetTimeFilter(range->first_ns, range->last_ns); !s.ok()) return s;
    if (livox_) layout_ = "livox_custom";
    else if (Status s = PeekLayout(); !s.ok()) return s;
    return Status::Ok();
  }

  StatusOr<SensorMessage> Next(ImuSample* imu, Scan* scan) override {
    RVLIO_CHECK(imu != nullptr && scan != nullptr);
    if (!error_.ok()) return error_;
    while (true) {
      StatusOr<bool> more = NextRaw();
      if (!more.ok()) return error_ = more.status();
      if (!*more) return SensorMessage::kEnd;
      const bool is_imu = message_.topic == imu_index_;
      StatusOr<bool> got = is_imu ? ReadImu(imu) : ReadScan(scan);
      if (!got.ok()) return error_ = got.status();
      if (*got) return is_imu ? SensorMessage::kImu : SensorMessage::kScan;
    }
  }

  Status RequireTopics() {
    const auto types = TopicTypes(*source_);
    const auto lidar_type = types.find(lidar_.topic);
    livox_ = lidar_type != types.end() && lidar_type->second == kLivoxRos2Type;
    if (Status s = RequireTopic(path_, types, lidar_.topic,
                                livox_ ? kLivoxRos2Type : cdr::kPointCloud2Type, "lidar.topic");
        !s.ok())
      return s;
    return RequireTopic(path_, types, imu_.topic, cdr::kImuType, "imu.topic");
  }

  // A topic missing from a file cut short is missing from the part that was
  // read (an MCAP file's channels may all sit after the cut): say so first.
  Status TruncationExplains(const Status& s) const {
    if (!source_->truncated()) return s;
    const std::vector<std::string> w = source_->warnings();
    return Status::InvalidInput("'" + path_ + "' is truncated (" +
                                (w.empty() ? std::string("cut short") : w.front()) +
                                "), and its readable part lacks a topic: " + s.message());
  }

  const SensorReaderStats& stats() const override { return gate_.stats(); }
  std::string lidar_layout() const override { return layout_; }
  std::vector<std::string> warnings() const override { return source_->warnings(); }
  bool truncated() const override { return source_->truncated(); }

 private:
  // Bytes of messages PeekLayout may hold before the first LiDAR message
  // (about two minutes of 400 Hz IMU samples).
  static constexpr size_t kPeekBytes = size_t{16} << 20;

  // Reads ahead to the first LiDAR message and detects its layout, so that a
  // cloud without a usable time field fails at Open, not minutes into a run.
  // The messages read ahead are kept for Next: the recording is read once
  // (a second reader would decompress the first MCAP chunk again). When the
  // first kPeekBytes hold no LiDAR message, the first scan Next decodes
  // detects the layout instead.
  Status PeekLayout() {
    size_t held_bytes = 0;
    while (held_bytes < kPeekBytes) {
      RawMessage m;
      StatusOr<bool> got = source_->Next(&m);
      if (!got.ok()) return got.status();
      if (!*got) return Status::Ok();
      held_bytes += sizeof(RawMessage) + m.data.size();
      peeked_.push_back(std::move(m));
      if (peeked_.back().topic == lidar_index_) return DetectLayout(peeked_.back());
    }
    return Status::Ok();
  }

  Status DetectLayout(const RawMessage& m) {
    StatusOr<PointCloud2View> cloud = cdr::DecodePointCloud2(m.data.data(), m.data.size(), lidar_.topic);
    if (!cloud.ok()) return InFile(cloud.status());
    StatusOr<std::string> layout = DetectPointCloud2Layout(*cloud, lidar_.type);
    if (!layout.ok()) return layout.status();
    layout_ = *layout;
    return Status::Ok();
  }

  // The next message: those PeekLayout read ahead first, then the source's.
  StatusOr<bool> NextRaw() {
    if (peeked_.empty()) return source_->Next(&message_);
    message_ = std::move(peeked_.front());
    peeked_.pop_front();
    return true;
  }

  Status InFile(const Status& s) const {
    return Status::InvalidInput("'" + path_ + "': " + s.message());
  }

  StatusOr<bool> ReadImu(ImuSample* out) {
    StatusOr<cdr::ImuMessage> msg =
        cdr::DecodeImu(message_.data.data(), message_.data.size(), imu_.topic);
    if (!msg.ok()) return InFile(msg.status());
    const auto& a = msg->linear_acceleration;
    const auto& w = msg->angular_velocity;
    return gate_.AcceptImu(msg->header_stamp_ns, Eigen::Vector3d(a[0], a[1], a[2]),
                           Eigen::Vector3d(w[0], w[1], w[2]), out);
  }

  StatusOr<bool> ReadScan(Scan* out) {
    DecodeStats decode;
    StatusOr<Scan> scan = livox_ ? DecodeLivox(&decode) : DecodeCloud(&decode);
    if (!scan.ok()) return scan.status();
    layout_ = decode.layout;
    return gate_.AcceptScan(decode, std::move(scan).value(), out);
  }

  StatusOr<Scan> DecodeCloud(DecodeStats* decode) const {
    StatusOr<PointCloud2View> cloud =
        cdr::DecodePointCloud2(message_.data.data(), message_.data.size(), lidar_.topic);
    if (!cloud.ok()) return InFile(cloud.status());
    return DecodePointCloud2(*cloud, lidar_, decode);
  }

  StatusOr<Scan> DecodeLivox(DecodeStats* decode) const {
    StatusOr<LivoxCustomMsg> msg =
        cdr::DecodeLivoxCustomMsg(message_.data.data(), message_.data.size(), lidar_.topic);
    if (!msg.ok()) return InFile(msg.status());
    StatusOr<Scan> scan = DecodeLivoxCustomMsg(*msg, lidar_, decode);
    if (!scan.ok())
      return Status::InvalidInput("lidar.topic '" + lidar_.topic + "' in '" + path_ +
                                  "': " + scan.status().message());
    return scan;
  }

  std::string path_;
  bool livox_ = false;  // the LiDAR topic holds livox_ros_driver2/msg/CustomMsg
  LidarOptions lidar_;
  ImuOptions imu_;
  SensorGate gate_;
  std::unique_ptr<RecordingSource> source_;
  int lidar_index_ = -1, imu_index_ = -1;
  RawMessage message_;
  std::deque<RawMessage> peeked_;  // read ahead by PeekLayout, not yet returned
  std::string layout_;
  Status error_;
};

}  // namespace

StatusOr<std::unique_ptr<SensorBagReader>> OpenRos2SensorReader(
    const std::string& path, const LidarOptions& lidar, const ImuOptions& imu,
    const std::optional<ReceiveTimeRange>& range) {
  auto reader = std::make_unique<Ros2SensorReader>(path, lidar, imu);
  if (Status s = reader->Init(range); !s.ok()) return s;
  return std::unique_ptr<SensorBagReader>(std::move(reader));
}

}  // namespace rvlio::bag_detail

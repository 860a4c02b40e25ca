// LiveSensorSource: network messages in, the estimator's SensorBagReader out.
#include "rvlio/formats/live_source.h"

#include <algorithm>
#include <array>
#include <limits>
#include <utility>

#include "rvlio/common/text.h"
#include "rvlio/formats/cdr.h"
#include "rvlio/formats/livox.h"
#include "rvlio/formats/pointcloud2.h"
#include "ouster_source.h"
#include "ros1_messages.h"
#include "sensor_reader_common.h"

namespace rvlio {

std::vector<std::string> LiveLidarTypes(WireEncoding encoding) {
  const bool ros2 = encoding == WireEncoding::kCdr;
  std::vector<std::string> types = ros2 ? std::vector<std::string>{cdr::kPointCloud2Type, kLivoxRos2Type}
                                        : std::vector<std::string>{bag_detail::kPointCloud2Type, kLivoxRos1Type};
  for (const std::string& t : bag_detail::OusterPacketTypes(ros2)) types.push_back(t);
  return types;
}

std::vector<std::string> LiveImuTypes(WireEncoding encoding) {
  const bool ros2 = encoding == WireEncoding::kCdr;
  std::vector<std::string> types{ros2 ? cdr::kImuType : bag_detail::kImuType};
  for (const std::string& t : bag_detail::OusterPacketTypes(ros2)) types.push_back(t);
  return types;
}

// The recording readers' decoders and acceptance rules for one encoding.
// Decode* run on the transport threads; the gate (and the IMU side of the
// Ouster packet decoder) is shared under gate_mutex_, the lidar side of the
// packet decoder (the frame being assembled) under lidar_mutex_.
class LiveSensorSource::Decoder {
 public:
  explicit Decoder(const LiveSourceOptions& o)
      : encoding_(o.encoding),
        lidar_(o.lidar),
        imu_(o.imu),
        origin_(o.origin),
        lidar_where_("lidar.topic '" + o.lidar.topic + "' (" + o.origin + ")"),
        imu_where_("imu.topic '" + o.imu.topic + "' (" + o.origin + ")"),
        gate_(o.imu, o.lidar, o.origin) {
    if (o.ouster)
      ouster_ = std::make_unique<bag_detail::OusterPacketDecoder>(*o.ouster, o.ouster_origin, o.lidar);
  }

  // The accepted samples: none for a dropped one, several for an Ouster IMU packet.
  StatusOr<std::vector<ImuSample>> Imu(const uint8_t* data, size_t size, const std::string& type) {
    const std::vector<std::string> types = LiveImuTypes(encoding_);
    if (std::find(types.begin(), types.end(), type) == types.end())
      return WrongType(imu_where_, type, types);
    if (bag_detail::IsOusterPacketType(type)) return ImuPacket(data, size, type);
    TimeNs stamp_ns = 0;
    std::array<double, 3> a{}, w{};
    if (encoding_ == WireEncoding::kRos1) {
      StatusOr<bag_detail::Ros1Imu> m = bag_detail::ParseRos1Imu(data, size, imu_where_);
      if (!m.ok()) return m.status();
      stamp_ns = m->header_stamp_ns, a = m->linear_acceleration, w = m->angular_velocity;
    } else {
      StatusOr<cdr::ImuMessage> m = cdr::DecodeImu(data, size, imu_.topic);
      if (!m.ok()) return InOrigin(m.status());
      stamp_ns = m->header_stamp_ns, a = m->linear_acceleration, w = m->angular_velocity;
    }
    std::lock_guard<std::mutex> lock(gate_mutex_);
    ImuSample sample;
    if (!gate_.AcceptImu(stamp_ns, Eigen::Vector3d(a[0], a[1], a[2]),
                         Eigen::Vector3d(w[0], w[1], w[2]), &sample))
      return std::vector<ImuSample>();
    return std::vector<ImuSample>{sample};
  }

  // True with *out set for a scan with points, false for an empty one or
  // (Ouster packets) a packet that did not complete a frame. The scan is on
  // the IMU clock (lidar.time_offset applied).
  StatusOr<bool> Lidar(const uint8_t* data, size_t size, const std::string& type, Scan* out) {
    const std::vector<std::string> types = LiveLidarTypes(encoding_);
    if (std::find(types.begin(), types.end(), type) == types.end())
      return WrongType(lidar_where_, type, types);
    DecodeStats decode;
    if (bag_detail::IsOusterPacketType(type)) {
      Scan frame;
      StatusOr<bool> completed = LidarPacket(data, size, type, &frame, &decode);
      if (!completed.ok() || !*completed) return completed;
      return Accept(decode, std::move(frame), out);
    }
    StatusOr<Scan> scan = type == types[1] ? DecodeLivox(data, size, &decode)
                                           : DecodeCloud(data, size, &decode);
    if (!scan.ok()) return scan.status();
    return Accept(decode, std::move(scan).value(), out);
  }

  // At the end of the input: the frame of Ouster packets being assembled,
  // as a packet recording's reader delivers it at its end.
  StatusOr<bool> FlushLidar(Scan* out) {
    if (!ouster_) return false;
    DecodeStats decode;
    Scan frame;
    {
      std::lock_guard<std::mutex> lock(lidar_mutex_);
      if (!ouster_->FlushLidar(&frame, &decode)) return false;
    }
    return Accept(decode, std::move(frame), out);
  }

  SensorReaderStats stats() const {
    std::lock_guard<std::mutex> lock(gate_mutex_);
    return gate_.stats();
  }
  std::string layout() const {
    std::lock_guard<std::mutex> lock(gate_mutex_);
    return layout_;
  }
  std::vector<std::string> warnings() const {
    if (!ouster_) return {};
    std::scoped_lock lock(lidar_mutex_, gate_mutex_);
    return ouster_->Warnings("Ouster packets (" + origin_ + ")");
  }

 private:
  // "... carries T, expected A, B or C".
  static Status WrongType(const std::string& where, const std::string& type,
                          const std::vector<std::string>& expected) {
    std::vector<std::string> head(expected.begin(), expected.end() - 1);
    const std::string list =
        head.empty() ? expected.back() : Join(head, ", ") + " or " + expected.back();
    return Status::InvalidInput(where + " carries " + type + ", expected " + list);
  }
  Status InOrigin(const Status& s) const {
    return Status::InvalidInput(s.message() + " (" + origin_ + ")");
  }

  // lidar.time_offset, then the acceptance rules.
  StatusOr<bool> Accept(const DecodeStats& decode, Scan&& scan, Scan* out) {
    if (lidar_.time_offset != 0.0) ShiftScanTime(SecondsToNs(lidar_.time_offset), &scan);
    std::lock_guard<std::mutex> lock(gate_mutex_);
    layout_ = decode.layout;
    return gate_.AcceptScan(decode, std::move(scan), out);
  }

  // The packet of a PacketMsg; InvalidInput without the sensor's metadata.
  StatusOr<std::vector<uint8_t>> PacketOf(const uint8_t* data, size_t size, const std::string& type,
                                          bag_detail::OusterPacketKind kind,
                                          const std::string& where) const {
    if (!ouster_)
      return Status::InvalidInput(where + " carries Ouster packets (" + type +
                                  "): give the sensor's metadata JSON with --ouster-metadata FILE "
                                  "(lidar.ouster_metadata)");
    StatusOr<std::vector<uint8_t>> bytes = encoding_ == WireEncoding::kRos1
                                               ? bag_detail::Ros1PacketBuffer(data, size, where)
                                               : bag_detail::CdrPacketBuffer(data, size, where);
    if (bytes.ok()) bag_detail::TrimDriverByte(ouster_->metadata(), kind, &*bytes);
    return bytes;
  }

  StatusOr<bool> LidarPacket(const uint8_t* data, size_t size, const std::string& type, Scan* frame,
                             DecodeStats* decode) {
    StatusOr<std::vector<uint8_t>> packet =
        PacketOf(data, size, type, bag_detail::OusterPacketKind::kLidar, lidar_where_);
    if (!packet.ok()) return packet.status();
    std::lock_guard<std::mutex> lock(lidar_mutex_);
    return ouster_->AddLidar(*packet, lidar_where_, frame, decode);
  }

  StatusOr<std::vector<ImuSample>> ImuPacket(const uint8_t* data, size_t size, const std::string& type) {
    StatusOr<std::vector<uint8_t>> packet =
        PacketOf(data, size, type, bag_detail::OusterPacketKind::kImu, imu_where_);
    if (!packet.ok()) return packet.status();
    std::lock_guard<std::mutex> lock(gate_mutex_);
    StatusOr<std::vector<ImuSample>> samples = ouster_->DecodeImu(*packet, imu_where_);
    if (!samples.ok()) return samples.status();
    std::vector<ImuSample> accepted;
    for (const ImuSample& s : *samples) {
      ImuSample out;
      if (gate_.AcceptSiImu(s.t_ns, s.acc_imu, s.gyro_imu, &out)) accepted.push_back(out);
    }
    return accepted;
  }

  StatusOr<Scan> DecodeCloud(const uint8_t* data, size_t size, DecodeStats* decode) const {
    StatusOr<PointCloud2View> cloud =
        encoding_ == WireEncoding::kRos1
            ? bag_detail::ParseRos1PointCloud2(data, size, lidar_.topic, lidar_where_)
            : cdr::DecodePointCloud2(data, size, lidar_.topic);
    if (!cloud.ok()) return encoding_ == WireEncoding::kCdr ? InOrigin(cloud.status()) : cloud.status();
    return DecodePointCloud2(*cloud, lidar_, decode);
  }

  StatusOr<Scan> DecodeLivox(const uint8_t* data, size_t size, DecodeStats* decode) const {
    StatusOr<LivoxCustomMsg> msg = encoding_ == WireEncoding::kRos1
                                       ? ParseLivoxRos1(data, size, lidar_where_)
                                       : cdr::DecodeLivoxCustomMsg(data, size, lidar_.topic);
    if (!msg.ok()) return encoding_ == WireEncoding::kCdr ? InOrigin(msg.status()) : msg.status();
    StatusOr<Scan> scan = DecodeLivoxCustomMsg(*msg, lidar_, decode);
    if (!scan.ok()) return Status::InvalidInput(lidar_where_ + ": " + scan.status().message());
    return scan;
  }

  WireEncoding encoding_;
  LidarOptions lidar_;
  ImuOptions imu_;
  std::string origin_, lidar_where_, imu_where_;
  mutable std::mutex gate_mutex_, lidar_mutex_;
  bag_detail::SensorGate gate_;
  std::string layout_;
  std::unique_ptr<bag_detail::OusterPacketDecoder> ouster_;
};

LiveSensorSource::LiveSensorSource(LiveSourceOptions options)
    : options_(std::move(options)),
      decoder_(std::make_unique<Decoder>(options_)),
      start_(std::chrono::steady_clock::now()) {}

LiveSensorSource::~LiveSensorSource() = default;

std::vector<ImuSample> LiveSensorSource::PushImu(const uint8_t* data, size_t size,
                                                 const std::string& type) {
  StatusOr<std::vector<ImuSample>> got = decoder_->Imu(data, size, type);
  std::lock_guard<std::mutex> lock(mutex_);
  if (ended_) return {};
  ++live_stats_.imu_messages;
  got_imu_ = true;
  if (!got.ok()) {
    if (error_.ok()) error_ = got.status();
    ready_cv_.notify_all();
    return {};
  }
  for (const ImuSample& sample : *got) QueueImu(sample);
  if (!got->empty()) ready_cv_.notify_all();
  return std::move(got).value();
}

void LiveSensorSource::QueueImu(const ImuSample& sample) {
  newest_imu_ns_ = sample.t_ns;
  ReleasePendingScans(sample.t_ns);
  if (ready_imu_ >= options_.live.imu_queue) {  // the estimator stalled: the oldest sample goes
    const auto oldest = std::find_if(ready_.begin(), ready_.end(), [](const Item& i) {
      return i.kind == SensorMessage::kImu;
    });
    ready_.erase(oldest);
    --ready_imu_;
    ++live_stats_.imu_dropped;
  }
  Item item;
  item.kind = SensorMessage::kImu;
  item.imu = sample;
  ready_.push_back(std::move(item));
  ++ready_imu_;
}

void LiveSensorSource::PushLidar(const uint8_t* data, size_t size, const std::string& type,
                                 std::chrono::steady_clock::time_point arrival) {
  Item item;
  item.kind = SensorMessage::kScan;
  item.arrival = arrival;
  StatusOr<bool> got = decoder_->Lidar(data, size, type, &item.scan);
  std::lock_guard<std::mutex> lock(mutex_);
  if (ended_) return;
  ++live_stats_.lidar_messages;
  got_lidar_ = true;
  if (!got.ok()) {
    if (error_.ok()) error_ = got.status();
    ready_cv_.notify_all();
    return;
  }
  if (*got) QueueScan(std::move(item));
  ready_cv_.notify_all();
}

// Pending scans are kept sorted by end time; at most scan_queue of them wait
// for the IMU (a LiDAR running without IMU drops its oldest ones).
void LiveSensorSource::QueueScan(Item item) {
  const TimeNs t_end = item.scan.t_end_ns;
  const auto at = std::find_if(pending_.begin(), pending_.end(),
                               [t_end](const Item& p) { return p.scan.t_end_ns > t_end; });
  pending_.insert(at, std::move(item));
  if (static_cast<int>(pending_.size()) > options_.live.scan_queue) {
    pending_.pop_front();
    ++live_stats_.scans_dropped;
  }
  // The IMU sample that covers it may have come while it was decoded.
  if (newest_imu_ns_ >= t_end) ReleasePendingScans(newest_imu_ns_);
}

void LiveSensorSource::ReleasePendingScans(TimeNs imu_t_ns) {
  const auto now = std::chrono::steady_clock::now();
  while (!pending_.empty() && pending_.front().scan.t_end_ns <= imu_t_ns) {
    pending_.front().covered = now;
    if (ready_scans_ >= options_.live.scan_queue) {  // the estimator fell behind
      const auto oldest = std::find_if(ready_.begin(), ready_.end(), [](const Item& i) {
        return i.kind == SensorMessage::kScan;
      });
      ready_.erase(oldest);
      --ready_scans_;
      ++live_stats_.scans_dropped;
    }
    ready_.push_back(std::move(pending_.front()));
    pending_.pop_front();
    ++ready_scans_;
  }
}

void LiveSensorSource::FlushAssembly() {
  Item item;
  item.kind = SensorMessage::kScan;
  item.arrival = std::chrono::steady_clock::now();
  StatusOr<bool> got = decoder_->FlushLidar(&item.scan);
  if (!got.ok()) {
    if (error_.ok()) error_ = got.status();
  } else if (*got) {
    QueueScan(std::move(item));
  }
}

void LiveSensorSource::Fail(const Status& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (error_.ok()) error_ = status;
  ready_cv_.notify_all();
}

Status LiveSensorSource::WaitTimeout() const {
  const double waited_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (waited_s < options_.lidar.wait_timeout) return Status::Ok();
  const std::string missing = !got_lidar_ ? "lidar.topic '" + options_.lidar.topic + "'"
                                          : "imu.topic '" + options_.imu.topic + "'";
  return Status::InvalidInput("no message on " + missing + " within lidar.wait_timeout " +
                              FormatFixed(options_.lidar.wait_timeout, 1) + " s (" +
                              options_.origin + "): is its publisher running?");
}

StatusOr<SensorMessage> LiveSensorSource::Next(ImuSample* imu, Scan* scan) {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    if (!error_.ok()) return error_;
    if (!ended_ && options_.stopped && options_.stopped()) {
      ended_ = true;  // the end of the input: what waits for the IMU is delivered first
      FlushAssembly();
      ReleasePendingScans(std::numeric_limits<TimeNs>::max());
      continue;  // an error of the last frame comes first
    }
    if (!ready_.empty()) break;
    if (ended_) return SensorMessage::kEnd;
    if (!(got_lidar_ && got_imu_))
      if (Status s = WaitTimeout(); !s.ok()) return error_ = s;
    ready_cv_.wait_for(lock, std::chrono::milliseconds(kLivePollMs));
  }
  Item item = std::move(ready_.front());
  ready_.pop_front();
  if (item.kind == SensorMessage::kImu) {
    --ready_imu_;
    *imu = item.imu;
    return SensorMessage::kImu;
  }
  --ready_scans_;
  lock.unlock();
  constexpr size_t kKeptArrivals = 16;
  if (handed_.size() >= kKeptArrivals) handed_.pop_front();
  handed_.push_back(LiveScanArrival{item.scan.t_end_ns, item.arrival, item.covered, item.scan});
  *scan = std::move(item.scan);
  return SensorMessage::kScan;
}

std::optional<LiveScanArrival> LiveSensorSource::TakeArrival(TimeNs t_end_ns) {
  std::optional<LiveScanArrival> found;
  while (!handed_.empty() && handed_.front().t_end_ns <= t_end_ns) {
    found = std::move(handed_.front());
    handed_.pop_front();
  }
  return found;
}

const SensorReaderStats& LiveSensorSource::stats() const {
  stats_copy_ = decoder_->stats();
  return stats_copy_;
}

std::string LiveSensorSource::lidar_layout() const { return decoder_->layout(); }

std::vector<std::string> LiveSensorSource::warnings() const { return decoder_->warnings(); }

Status LiveSensorSource::error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

LiveSourceStats LiveSensorSource::live_stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return live_stats_;
}

}  // namespace rvlio

// The SensorBagReader of Ouster packet recordings (a capture or a packet
// bag, ouster_source.h): IMU packets become samples as they come, lidar
// packets are assembled into one scan per frame (OusterScanAssembler).
#include <cstdio>
#include <deque>

#include "ouster_source.h"
#include "sensor_reader_common.h"

namespace rvlio {
namespace bag_detail {

OusterPacketDecoder::OusterPacketDecoder(OusterMetadata meta, std::string metadata_origin,
                                         const LidarOptions& lidar)
    : meta_(std::move(meta)), metadata_origin_(std::move(metadata_origin)), assembler_(meta_, lidar) {}

StatusOr<OusterLidarPacket> OusterPacketDecoder::DecodeLidar(const std::vector<uint8_t>& bytes,
                                                             const std::string& where) {
  if (!meta_.lidar_profile_decoded)
    return Status::InvalidInput(where + ": lidar packets of profile " + meta_.lidar_profile_name +
                                " (metadata " + metadata_origin_ + "), which rvlio does not decode");
  StatusOr<OusterLidarPacket> packet = DecodeOusterLidarPacket(
      meta_, bytes.data(), bytes.size(), where + " (metadata " + metadata_origin_ + ")");
  if (!packet.ok()) return packet;
  if (packet->init_id >= 0 && meta_.initialization_id >= 0 && packet->init_id != meta_.initialization_id)
    return Status::InvalidInput(where + ": lidar packets of initialization id " +
                                std::to_string(packet->init_id) + ", metadata " + metadata_origin_ +
                                " of " + std::to_string(meta_.initialization_id) +
                                " (metadata of another sensor or session)");
  if (!first_decoded_) {
    first_decoded_ = true;
    crc_checked_ = packet->crc_present;
  }
  return packet;
}

StatusOr<bool> OusterPacketDecoder::AddLidar(const std::vector<uint8_t>& bytes, const std::string& where,
                                             Scan* scan, DecodeStats* decode) {
  StatusOr<OusterLidarPacket> packet = DecodeLidar(bytes, where);
  if (!packet.ok()) return packet.status();
  if (crc_checked_ && !packet->crc_present) {
    ++assembler_.mutable_stats().crc_errors;
    return false;
  }
  return assembler_.Add(*packet, scan, decode);
}

bool OusterPacketDecoder::FlushLidar(Scan* scan, DecodeStats* decode) {
  return assembler_.Flush(scan, decode);
}

StatusOr<std::vector<ImuSample>> OusterPacketDecoder::DecodeImu(const std::vector<uint8_t>& bytes,
                                                                const std::string& where) {
  bool crc_ok = true;
  StatusOr<std::vector<ImuSample>> samples =
      DecodeOusterImuSamples(meta_, bytes.data(), bytes.size(), where, &crc_ok);
  if (!samples.ok()) return samples;
  ++imu_packets_;
  if (crc_ok) return samples;
  ++imu_crc_errors_;
  return std::vector<ImuSample>();
}

OusterFrameStats OusterPacketDecoder::stats() const {
  OusterFrameStats s = assembler_.stats();
  s.imu_packets = imu_packets_;
  s.imu_crc_errors = imu_crc_errors_;
  return s;
}

std::vector<std::string> OusterPacketDecoder::Warnings(const std::string& source) const {
  const OusterFrameStats s = stats();
  std::vector<std::string> out;
  if (s.incomplete_frames > 0)
    out.push_back(source + ": " + std::to_string(s.incomplete_frames) +
                  " frames with missing columns (" + std::to_string(s.missing_columns) +
                  " columns absent: dropped packets), used with what they have");
  if (s.late_packets > 0)
    out.push_back(source + ": " + std::to_string(s.late_packets) +
                  " lidar packets of an already completed frame dropped");
  if (s.imu_crc_errors > 0)
    out.push_back(source + ": " + std::to_string(s.imu_crc_errors) +
                  " IMU packets with a wrong CRC-64 dropped");
  if (s.crc_errors > 0)
    out.push_back(source + ": " + std::to_string(s.crc_errors) +
                  " lidar packets with a wrong CRC-64 dropped");
  return out;
}

namespace {

class OusterSensorReader final : public SensorBagReader {
 public:
  OusterSensorReader(std::unique_ptr<OusterPacketSource> source, const LidarOptions& lidar,
                     const ImuOptions& imu)
      : source_(std::move(source)), gate_(imu, lidar, source_->path()),
        packets_(source_->metadata(), source_->metadata_origin(), lidar) {}

  // Reads ahead to the first lidar packet and decodes it, so that metadata
  // of another mode or profile fails at Open.
  Status Init() {
    while (true) {
      OusterRawPacket p;
      StatusOr<bool> got = source_->Next(&p);
      if (!got.ok()) return got.status();
      if (!*got) return Status::Ok();
      peeked_.push_back(std::move(p));
      if (peeked_.back().kind != OusterPacketKind::kLidar) continue;
      return packets_.DecodeLidar(peeked_.back().bytes, Where(peeked_.back())).status();
    }
  }

  StatusOr<SensorMessage> Next(ImuSample* imu, Scan* scan) override {
    RVLIO_CHECK(imu != nullptr && scan != nullptr);
    if (!error_.ok()) return error_;
    StatusOr<SensorMessage> m = Step(imu, scan);
    if (!m.ok()) error_ = m.status();
    return m;
  }

  const SensorReaderStats& stats() const override { return gate_.stats(); }
  OusterFrameStats frame_stats() const { return packets_.stats(); }
  const OusterPacketSource& source() const { return *source_; }
  bool crc_checked() const { return packets_.crc_checked(); }
  std::string lidar_layout() const override { return "ouster_packets"; }
  std::vector<std::string> warnings() const override {
    std::vector<std::string> out = packets_.Warnings("'" + source_->path() + "'");
    if (packets_.stats().lidar_packets == 0)
      out.push_back("'" + source_->path() + "': no lidar packets (IMU samples only)");
    return out;
  }

 private:
  StatusOr<SensorMessage> Step(ImuSample* imu, Scan* scan) {
    while (true) {
      while (!pending_imu_.empty()) {
        const ImuSample s = pending_imu_.front();
        pending_imu_.pop_front();
        if (gate_.AcceptSiImu(s.t_ns, s.acc_imu, s.gyro_imu, imu)) return SensorMessage::kImu;
      }
      OusterRawPacket p;
      StatusOr<bool> got = NextPacket(&p);
      if (!got.ok()) return got.status();
      if (!*got) {
        DecodeStats decode;
        Scan last;
        while (packets_.FlushLidar(&last, &decode)) {
          StatusOr<bool> accepted = gate_.AcceptScan(decode, std::move(last), scan);
          if (!accepted.ok()) return accepted.status();
          if (*accepted) return SensorMessage::kScan;
        }
        return SensorMessage::kEnd;
      }
      if (p.kind == OusterPacketKind::kImu) {
        StatusOr<std::vector<ImuSample>> samples = packets_.DecodeImu(p.bytes, Where(p));
        if (!samples.ok()) return samples.status();
        pending_imu_.insert(pending_imu_.end(), samples->begin(), samples->end());
        continue;
      }
      DecodeStats decode;
      Scan done;
      StatusOr<bool> completed = packets_.AddLidar(p.bytes, Where(p), &done, &decode);
      if (!completed.ok()) return completed.status();
      if (!*completed) continue;
      StatusOr<bool> accepted = gate_.AcceptScan(decode, std::move(done), scan);
      if (!accepted.ok()) return accepted.status();
      if (*accepted) return SensorMessage::kScan;
    }
  }

  StatusOr<bool> NextPacket(OusterRawPacket* out) {
    if (peeked_.empty()) return source_->Next(out);
    *out = std::move(peeked_.front());
    peeked_.pop_front();
    return true;
  }

  std::string Where(const OusterRawPacket& p) const {
    return "'" + source_->path() + "' " +
           (p.kind == OusterPacketKind::kLidar ? source_->lidar_origin() : source_->imu_origin());
  }

  std::unique_ptr<OusterPacketSource> source_;
  SensorGate gate_;
  OusterPacketDecoder packets_;
  std::deque<OusterRawPacket> peeked_;
  std::deque<ImuSample> pending_imu_;
  Status error_;
};

double Rate(int64_t n, TimeNs first_ns, TimeNs last_ns) {
  return n > 1 && last_ns > first_ns ? (n - 1) / NsToSeconds(last_ns - first_ns) : 0.0;
}

}  // namespace

StatusOr<OusterRecordingInfo> ReadOusterRecordingInfo(const std::string& path, RecordingKind kind,
                                                      const std::string& metadata_path) {
  StatusOr<std::unique_ptr<OusterPacketSource>> source =
      kind == RecordingKind::kPcap ? OpenOusterPcapSource(path, metadata_path, std::nullopt)
                                   : OpenOusterBagSource(path, kind, metadata_path, std::nullopt);
  if (!source.ok()) return source.status();
  LidarOptions lidar;  // count every return: no range crop
  lidar.min_range = 0.0;
  lidar.max_range = 1e9;
  ImuOptions imu;
  imu.max_gap = 1e9;
  OusterSensorReader reader(std::move(source).value(), lidar, imu);
  if (Status s = reader.Init(); !s.ok()) return s;
  ImuSample sample;
  Scan scan;
  int64_t imu_n = 0, scans_n = 0;
  TimeNs imu_first = 0, imu_last = 0, scan_first = 0, scan_last = 0;
  while (true) {
    StatusOr<SensorMessage> m = reader.Next(&sample, &scan);
    if (!m.ok()) return m.status();
    if (*m == SensorMessage::kEnd) break;
    if (*m == SensorMessage::kImu) {
      if (imu_n++ == 0) imu_first = sample.t_ns;
      imu_last = sample.t_ns;
    } else {
      if (scans_n++ == 0) scan_first = scan.t_start_ns;
      scan_last = scan.t_start_ns;
    }
  }
  const OusterMetadata& meta = reader.source().metadata();
  const OusterFrameStats f = reader.frame_stats();
  OusterRecordingInfo info;
  info.metadata = reader.source().metadata_origin();
  info.prod_line = meta.prod_line;
  info.firmware = meta.firmware;
  info.lidar_mode = meta.lidar_mode;
  info.lidar_profile = meta.lidar_profile_name;
  info.imu_profile = meta.imu_profile;
  info.lidar_decoded = meta.lidar_profile_decoded;
  info.beams = meta.pixels_per_column;
  info.columns_per_frame = meta.columns_per_frame;
  info.window_columns = meta.WindowColumns();
  info.lidar_source = reader.source().lidar_origin();
  info.imu_source = reader.source().imu_origin();
  info.lidar_packets = f.lidar_packets;
  info.imu_packets = f.imu_packets;
  info.frames = f.frames;
  info.incomplete_frames = f.incomplete_frames;
  info.missing_columns = f.missing_columns;
  info.late_packets = f.late_packets;
  info.crc_errors = f.crc_errors;
  info.imu_crc_errors = f.imu_crc_errors;
  info.crc = reader.crc_checked();
  info.imu_rate_hz = Rate(imu_n, imu_first, imu_last);
  info.frame_rate_hz = Rate(scans_n, scan_first, scan_last);
  return info;
}

StatusOr<std::unique_ptr<SensorBagReader>> OpenOusterReader(
    std::unique_ptr<OusterPacketSource> source, const LidarOptions& lidar, const ImuOptions& imu) {
  auto reader = std::make_unique<OusterSensorReader>(std::move(source), lidar, imu);
  if (Status s = reader->Init(); !s.ok()) return s;
  return std::unique_ptr<SensorBagReader>(std::move(reader));
}


}  // namespace bag_detail


void ApplyOusterExtrinsics(const OusterMetadata& meta, const std::string& origin,
                           ExtrinsicsSection* extrinsics, std::vector<std::string>* notes) {
  const ExtrinsicsOptions defaults;
  ExtrinsicsOptions& e = extrinsics->imu_T_lidar;
  if (e.translation != defaults.translation || e.rotation_xyzw != defaults.rotation_xyzw) return;
  const Eigen::Isometry3d imu_T_lidar = OusterImuTLidar(meta);
  const Eigen::Quaterniond q(imu_T_lidar.linear());
  const Eigen::Vector3d t = imu_T_lidar.translation();
  e.translation = {t.x(), t.y(), t.z()};
  e.rotation_xyzw = {q.x(), q.y(), q.z(), q.w()};
  char line[256];
  std::snprintf(line, sizeof(line),
                "extrinsics.imu_T_lidar from the Ouster metadata %s (imu_to_sensor_transform): "
                "translation [%.6f, %.6f, %.6f] m, rotation_xyzw [%.6f, %.6f, %.6f, %.6f]",
                origin.c_str(), t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
  notes->push_back(line);
}

Status ApplyRecordingExtrinsics(const std::string& path, const LidarOptions& lidar,
                                ExtrinsicsSection* extrinsics, std::vector<std::string>* notes) {
  const ExtrinsicsOptions defaults;
  const ExtrinsicsOptions& e = extrinsics->imu_T_lidar;
  if (e.translation != defaults.translation || e.rotation_xyzw != defaults.rotation_xyzw)
    return Status::Ok();
  StatusOr<RecordingKind> kind = DetectRecording(path);
  if (!kind.ok()) return kind.status();
  StatusOr<bool> packets = bag_detail::HoldsOusterPackets(path, *kind, lidar.topic);
  if (!packets.ok() || !*packets) return packets.status();
  StatusOr<std::unique_ptr<bag_detail::OusterPacketSource>> source =
      *kind == RecordingKind::kPcap
          ? bag_detail::OpenOusterPcapSource(path, lidar.ouster_metadata, std::nullopt)
          : bag_detail::OpenOusterBagSource(path, *kind, lidar.ouster_metadata, std::nullopt);
  if (!source.ok()) return source.status();
  ApplyOusterExtrinsics((*source)->metadata(), (*source)->metadata_origin(), extrinsics, notes);
  return Status::Ok();
}

}  // namespace rvlio

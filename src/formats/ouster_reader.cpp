// The SensorBagReader of Ouster packet recordings (a capture or a packet
// bag, ouster_source.h): IMU packets become samples as they come, lidar
// packets are assembled into one scan per frame (OusterScanAssembler).
#include <cstdio>
#include <deque>

#include "ouster_source.h"
#include "sensor_reader_common.h"

namespace rvlio::bag_detail {
namespace {

// The gate receives SI accelerations: the packet's g are converted here.
ImuOptions SiImu(ImuOptions imu) {
  imu.accel_unit = "mps2";
  return imu;
}

class OusterSensorReader final : public SensorBagReader {
 public:
  OusterSensorReader(std::unique_ptr<OusterPacketSource> source, const LidarOptions& lidar,
                     const ImuOptions& imu)
      : source_(std::move(source)), gate_(SiImu(imu), lidar, source_->path()),
        assembler_(source_->metadata(), lidar) {}

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
      StatusOr<OusterLidarPacket> first = Decode(peeked_.back());
      return first.ok() ? Status::Ok() : first.status();
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
  const OusterFrameStats& frame_stats() const { return assembler_.stats(); }
  const OusterPacketSource& source() const { return *source_; }
  bool crc_checked() const { return crc_checked_; }
  std::string lidar_layout() const override { return "ouster_packets"; }
  std::vector<std::string> warnings() const override {
    const OusterFrameStats& s = assembler_.stats();
    std::vector<std::string> out;
    if (s.incomplete_frames > 0)
      out.push_back("'" + source_->path() + "': " + std::to_string(s.incomplete_frames) +
                    " frames with missing columns (" + std::to_string(s.missing_columns) +
                    " columns absent: dropped packets), used with what they have");
    if (s.late_packets > 0)
      out.push_back("'" + source_->path() + "': " + std::to_string(s.late_packets) +
                    " lidar packets of an already completed frame dropped");
    if (s.imu_crc_errors > 0)
      out.push_back("'" + source_->path() + "': " + std::to_string(s.imu_crc_errors) +
                    " IMU packets with a wrong CRC-64 dropped");
    if (s.lidar_packets == 0)
      out.push_back("'" + source_->path() + "': no lidar packets (IMU samples only)");
    if (s.crc_errors > 0)
      out.push_back("'" + source_->path() + "': " + std::to_string(s.crc_errors) +
                    " lidar packets with a wrong CRC-64 dropped");
    return out;
  }

 private:
  StatusOr<SensorMessage> Step(ImuSample* imu, Scan* scan) {
    while (true) {
      while (!pending_imu_.empty()) {
        const ImuSample s = pending_imu_.front();
        pending_imu_.pop_front();
        if (gate_.AcceptImu(s.t_ns, s.acc_imu, s.gyro_imu, imu)) return SensorMessage::kImu;
      }
      OusterRawPacket p;
      StatusOr<bool> got = NextPacket(&p);
      if (!got.ok()) return got.status();
      if (!*got) {
        DecodeStats decode;
        Scan last;
        while (assembler_.Flush(&last, &decode)) {
          StatusOr<bool> accepted = gate_.AcceptScan(decode, std::move(last), scan);
          if (!accepted.ok()) return accepted.status();
          if (*accepted) return SensorMessage::kScan;
        }
        return SensorMessage::kEnd;
      }
      if (p.kind == OusterPacketKind::kImu) {
        if (Status s = DecodeImu(p); !s.ok()) return s;
        continue;
      }
      StatusOr<OusterLidarPacket> packet = Decode(p);
      if (!packet.ok()) return packet.status();
      if (crc_checked_ && !packet->crc_present) {
        ++assembler_.mutable_stats().crc_errors;
        continue;
      }
      DecodeStats decode;
      Scan done;
      if (!assembler_.Add(*packet, &done, &decode)) continue;
      StatusOr<bool> accepted = gate_.AcceptScan(decode, std::move(done), scan);
      if (!accepted.ok()) return accepted.status();
      if (*accepted) return SensorMessage::kScan;
    }
  }

  // Queues the packet's samples (one LEGACY, several ACCEL32_GYRO32_NMEA);
  // a packet with a wrong CRC-64 is dropped and counted.
  Status DecodeImu(const OusterRawPacket& p) {
    bool crc_ok = true;
    StatusOr<std::vector<ImuSample>> samples =
        DecodeOusterImuSamples(source_->metadata(), p.bytes.data(), p.bytes.size(), Where(p), &crc_ok);
    if (!samples.ok()) return samples.status();
    OusterFrameStats& stats = assembler_.mutable_stats();
    ++stats.imu_packets;
    if (!crc_ok) {
      ++stats.imu_crc_errors;
      return Status::Ok();
    }
    pending_imu_.insert(pending_imu_.end(), samples->begin(), samples->end());
    return Status::Ok();
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

  // Decodes and checks the packet against the metadata's sensor: the
  // initialization id, when both carry one, and the CRC-64 once the first
  // packet showed that the firmware writes it.
  StatusOr<OusterLidarPacket> Decode(const OusterRawPacket& p) {
    const OusterMetadata& meta = source_->metadata();
    if (!meta.lidar_profile_decoded)
      return Status::InvalidInput(Where(p) + ": lidar packets of profile " + meta.lidar_profile_name +
                                  " (metadata " + source_->metadata_origin() +
                                  "), which rvlio does not decode");
    StatusOr<OusterLidarPacket> packet = DecodeOusterLidarPacket(
        meta, p.bytes.data(), p.bytes.size(), Where(p) + " (metadata " + source_->metadata_origin() + ")");
    if (!packet.ok()) return packet;
    if (packet->init_id >= 0 && meta.initialization_id >= 0 && packet->init_id != meta.initialization_id)
      return Status::InvalidInput(Where(p) + ": lidar packets of initialization id " +
                                  std::to_string(packet->init_id) + ", metadata " +
                                  source_->metadata_origin() + " of " +
                                  std::to_string(meta.initialization_id) +
                                  " (metadata of another sensor or session)");
    if (!first_decoded_) {
      first_decoded_ = true;
      crc_checked_ = packet->crc_present;
    }
    return packet;
  }

  std::unique_ptr<OusterPacketSource> source_;
  SensorGate gate_;
  OusterScanAssembler assembler_;
  std::deque<OusterRawPacket> peeked_;
  std::deque<ImuSample> pending_imu_;
  bool first_decoded_ = false, crc_checked_ = false;
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
  const OusterFrameStats& f = reader.frame_stats();
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

}  // namespace rvlio::bag_detail

namespace rvlio {

Status ApplyRecordingExtrinsics(const std::string& path, const LidarOptions& lidar,
                                ExtrinsicsSection* extrinsics, std::vector<std::string>* notes) {
  const ExtrinsicsOptions defaults;
  ExtrinsicsOptions& e = extrinsics->imu_T_lidar;
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
  const Eigen::Isometry3d imu_T_lidar = OusterImuTLidar((*source)->metadata());
  const Eigen::Quaterniond q(imu_T_lidar.linear());
  const Eigen::Vector3d t = imu_T_lidar.translation();
  e.translation = {t.x(), t.y(), t.z()};
  e.rotation_xyzw = {q.x(), q.y(), q.z(), q.w()};
  char line[256];
  std::snprintf(line, sizeof(line),
                "extrinsics.imu_T_lidar from the Ouster metadata %s (imu_to_sensor_transform): "
                "translation [%.6f, %.6f, %.6f] m, rotation_xyzw [%.6f, %.6f, %.6f, %.6f]",
                (*source)->metadata_origin().c_str(), t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
  notes->push_back(line);
  return Status::Ok();
}

}  // namespace rvlio

namespace rvlio::bag_detail {

StatusOr<std::unique_ptr<SensorBagReader>> OpenOusterReader(
    std::unique_ptr<OusterPacketSource> source, const LidarOptions& lidar, const ImuOptions& imu) {
  auto reader = std::make_unique<OusterSensorReader>(std::move(source), lidar, imu);
  if (Status s = reader->Init(); !s.ok()) return s;
  return std::unique_ptr<SensorBagReader>(std::move(reader));
}

}  // namespace rvlio::bag_detail

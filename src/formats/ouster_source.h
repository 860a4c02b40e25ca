#pragma once
// Private (src/formats only): where Ouster packets come from. A capture (.pcap +
// metadata JSON) or a packet bag (ROS1 ouster_ros/PacketMsg, ROS 2
// ouster_sensor_msgs/msg/PacketMsg, metadata on a String topic) gives the
// same stream of raw lidar and IMU packets with their receive times; one
// SensorBagReader (ouster_reader.cpp) decodes them.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/formats/ouster.h"
#include "rvlio/formats/recording.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio::bag_detail {

enum class OusterPacketKind { kLidar, kImu };

struct OusterRawPacket {
  OusterPacketKind kind = OusterPacketKind::kLidar;
  TimeNs receive_ns = 0;
  std::vector<uint8_t> bytes;
};

class OusterPacketSource {
 public:
  virtual ~OusterPacketSource() = default;
  // The next packet received in the range given at open; false at the end.
  virtual StatusOr<bool> Next(OusterRawPacket* out) = 0;
  virtual const OusterMetadata& metadata() const = 0;
  virtual std::string storage() const = 0;          // "pcap", "ros1", "sqlite3", "mcap"
  virtual std::string metadata_origin() const = 0;  // the JSON file or the topic
  // Where lidar / IMU packets come from ("udp port 7502", a topic).
  virtual std::string lidar_origin() const = 0;
  virtual std::string imu_origin() const = 0;
  const std::string& path() const { return path_; }

 protected:
  explicit OusterPacketSource(std::string path) : path_(std::move(path)) {}
  std::string path_;
};

// ROS1 / ROS 2 message types of the drivers' packet topics.
bool IsOusterPacketType(const std::string& type);
// "ouster_ros/PacketMsg"; "ouster_sensor_msgs/msg/PacketMsg", "ouster_msgs/msg/PacketMsg".
std::vector<std::string> OusterPacketTypes(bool ros2);

// The packet a driver's PacketMsg (uint8[] buf) holds: ROS 1 wire format
// (uint32 length + bytes) or CDR with its encapsulation header.
// InvalidInput naming `where` when the message is not one.
StatusOr<std::vector<uint8_t>> Ros1PacketBuffer(const uint8_t* data, size_t size,
                                                const std::string& where);
StatusOr<std::vector<uint8_t>> CdrPacketBuffer(const uint8_t* data, size_t size,
                                               const std::string& where);
// Strips the driver's extra trailing byte (ouster_ros buffers are one byte
// longer than the packet) when the rest is exactly a packet of `kind`.
void TrimDriverByte(const OusterMetadata& meta, OusterPacketKind kind, std::vector<uint8_t>* bytes);

// Lidar and IMU packets of one sensor -> scans and IMU samples (SI units):
// the one decoding of Ouster packets, for recordings (OusterSensorReader)
// and `rvlio live` (LiveSensorSource). The lidar calls (DecodeLidar,
// AddLidar, FlushLidar) and DecodeImu touch separate state, so one thread
// may feed the lidar packets while another feeds the IMU packets; stats()
// and Warnings() want both quiet.
class OusterPacketDecoder {
 public:
  OusterPacketDecoder(OusterMetadata meta, std::string metadata_origin, const LidarOptions& lidar);

  // A lidar packet checked against the metadata: a profile rvlio decodes,
  // the profile's packet size, the initialization id where both carry one
  // (InvalidInput naming `where` and the metadata). The first one decoded
  // says whether the firmware writes a CRC-64.
  StatusOr<OusterLidarPacket> DecodeLidar(const std::vector<uint8_t>& bytes, const std::string& where);
  // DecodeLidar, then assembly: true with *scan set when the packet
  // completed a frame. A packet without a matching CRC-64 (when the firmware
  // writes one) is dropped and counted.
  StatusOr<bool> AddLidar(const std::vector<uint8_t>& bytes, const std::string& where, Scan* scan,
                          DecodeStats* decode);
  // The frame being assembled, if any columns are pending.
  bool FlushLidar(Scan* scan, DecodeStats* decode);
  // The samples of an IMU packet, oldest first; none when its CRC-64 does
  // not match (counted). InvalidInput naming `where` for another size.
  StatusOr<std::vector<ImuSample>> DecodeImu(const std::vector<uint8_t>& bytes, const std::string& where);

  OusterFrameStats stats() const;
  bool crc_checked() const { return crc_checked_; }
  const OusterMetadata& metadata() const { return meta_; }
  const std::string& metadata_origin() const { return metadata_origin_; }
  // One line each for frames with missing columns, late packets and
  // packets with a wrong CRC-64, naming `source`.
  std::vector<std::string> Warnings(const std::string& source) const;

 private:
  OusterMetadata meta_;
  std::string metadata_origin_;
  OusterScanAssembler assembler_;  // lidar side
  bool first_decoded_ = false, crc_checked_ = false;
  int64_t imu_packets_ = 0, imu_crc_errors_ = 0;  // IMU side
};
// True when the recording's topics hold Ouster packets and `lidar_topic` is
// not a point cloud topic of it (a bag with both reads the clouds).
bool UsesOusterPackets(const std::map<std::string, std::string>& topic_types,
                       const std::string& lidar_topic);

// True for a pcap capture, or a bag whose topics hold Ouster packets
// (UsesOusterPackets); opens a bag to list its topics.
StatusOr<bool> HoldsOusterPackets(const std::string& path, RecordingKind kind,
                                  const std::string& lidar_topic);

// The metadata JSON of a capture: `explicit_path` when given, else next to
// the capture: STEM.json, STEM_0.json, or the longest NAME.json whose NAME_
// begins STEM (a capture cut from a longer recording keeps its prefix).
StatusOr<std::string> FindOusterMetadata(const std::string& pcap_path,
                                         const std::string& explicit_path);

StatusOr<std::unique_ptr<OusterPacketSource>> OpenOusterPcapSource(
    const std::string& path, const std::string& metadata_path,
    const std::optional<ReceiveTimeRange>& range);
StatusOr<std::unique_ptr<OusterPacketSource>> OpenOusterBagSource(
    const std::string& path, RecordingKind kind, const std::string& metadata_path,
    const std::optional<ReceiveTimeRange>& range);

// A pass over every packet of an Ouster recording (ouster_reader.cpp).
StatusOr<OusterRecordingInfo> ReadOusterRecordingInfo(const std::string& path, RecordingKind kind,
                                                      const std::string& metadata_path);

// The SensorBagReader over a packet source (ouster_reader.cpp).
StatusOr<std::unique_ptr<SensorBagReader>> OpenOusterReader(
    std::unique_ptr<OusterPacketSource> source, const LidarOptions& lidar, const ImuOptions& imu);

}  // namespace rvlio::bag_detail

#pragma once
// Private (src/formats only): where Ouster packets come from. A capture (.pcap +
// metadata JSON) or a packet bag (ROS1 ouster_ros/PacketMsg, ROS 2
// ouster_sensor_msgs/msg/PacketMsg, metadata on a String topic) gives the
// same stream of raw lidar and IMU packets with their receive times; one
// SensorBagReader (ouster_reader.cpp) decodes them.
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
StatusOr<OusterMetadata> ReadOusterMetadataFile(const std::string& path);

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

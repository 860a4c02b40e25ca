// SensorBagReader::Open: the one entry to every recording kind. Detects the
// kind from the file and hands it to its reader (ROS1 bag, ROS 2 .db3/.mcap,
// Ouster packets in a bag or a pcap).
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "ouster_source.h"
#include "rvlio/formats/recording.h"
#include "rvlio/formats/sensor_bag.h"
#include "sensor_reader_common.h"

namespace rvlio {

StatusOr<std::unique_ptr<SensorBagReader>> SensorBagReader::Open(
    const std::string& path, const LidarOptions& lidar, const ImuOptions& imu,
    const std::optional<ReceiveTimeRange>& range) {
  StatusOr<RecordingKind> kind = DetectRecording(path);
  if (!kind.ok()) return kind.status();
  StatusOr<bool> packets = bag_detail::HoldsOusterPackets(path, *kind, lidar.topic);
  if (!packets.ok()) return packets.status();
  if (*packets) {
    StatusOr<std::unique_ptr<bag_detail::OusterPacketSource>> source =
        *kind == RecordingKind::kPcap
            ? bag_detail::OpenOusterPcapSource(path, lidar.ouster_metadata, range)
            : bag_detail::OpenOusterBagSource(path, *kind, lidar.ouster_metadata, range);
    if (!source.ok()) return source.status();
    return bag_detail::OpenOusterReader(std::move(source).value(), lidar, imu);
  }
  if (*kind != RecordingKind::kRos1Bag)
    return bag_detail::OpenRos2SensorReader(path, lidar, imu, range);
  return bag_detail::OpenRos1SensorReader(path, lidar, imu, range);
}

}  // namespace rvlio

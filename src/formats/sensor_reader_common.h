#pragma once
// Private, ROS-free pieces shared by the ROS1 and ROS 2 sensor readers and
// `rvlio info` (src/formats only): topic checks with their messages, and the one
// place that decides which IMU samples and scans are delivered and counts
// what was dropped (SensorReaderStats).
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"
#include "rvlio/common/types.h"
#include "rvlio/imu/options.h"
#include "rvlio/lidar/options.h"
#include "rvlio/formats/pointcloud2.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio::bag_detail {

// "/a (sensor_msgs/Imu), /b (sensor_msgs/PointCloud2)" or "none".
std::string DescribeTopics(const std::map<std::string, std::string>& topics);

// InvalidInput unless `topic` is in the bag with message type `type`.
Status RequireTopic(const std::string& path, const std::map<std::string, std::string>& topics,
                    const std::string& topic, const std::string& type, const std::string& key);

// Applies the reader's acceptance rules and keeps SensorReaderStats.
class SensorGate {
 public:
  // `path`: the recording, for messages.
  SensorGate(const ImuOptions& imu, const LidarOptions& lidar, std::string path)
      : imu_(imu), lidar_(lidar), path_(std::move(path)) {}
  // An IMU message: acc in imu.accel_unit (scaled to m/s^2 here), gyro in
  // rad/s. True when *out holds a new sample; false when it was dropped
  // (non-finite, duplicate or older stamp).
  bool AcceptImu(TimeNs t_ns, const Eigen::Vector3d& acc, const Eigen::Vector3d& gyro,
                 ImuSample* out);
  // The same for a sample in m/s^2 whatever imu.accel_unit says (Ouster IMU
  // packets state their own unit).
  bool AcceptSiImu(TimeNs t_ns, const Eigen::Vector3d& acc_mps2, const Eigen::Vector3d& gyro,
                   ImuSample* out);
  // A decoded scan: counts the dropped points; true (and moves the scan into
  // *out) when it has points, false for an empty scan. InvalidInput when the
  // point times of the first scans span less than lidar.point_time_span_stop
  // of the scan period (CheckPointTimes).
  StatusOr<bool> AcceptScan(const DecodeStats& decode, Scan&& scan, Scan* out);
  const SensorReaderStats& stats() const { return stats_; }

 private:
  bool AcceptImuStamp(TimeNs t_ns);
  Status CheckPointTimes(const Scan& scan);

  ImuOptions imu_;
  LidarOptions lidar_;
  std::string path_;
  std::vector<TimeNs> first_starts_ns_, first_spans_ns_;  // of the first scans
  SensorReaderStats stats_;
  bool have_imu_ = false;
  TimeNs last_imu_ns_ = 0;
};

// The SensorBagReader of a ROS 2 recording (.db3, .mcap or bag folder);
// src/formats/ros2_sensor_reader.cpp.
StatusOr<std::unique_ptr<SensorBagReader>> OpenRos2SensorReader(
    const std::string& path, const LidarOptions& lidar, const ImuOptions& imu,
    const std::optional<ReceiveTimeRange>& range);

// The SensorBagReader of a ROS1 bag; src/formats/sensor_bag_reader.cpp.
StatusOr<std::unique_ptr<SensorBagReader>> OpenRos1SensorReader(
    const std::string& path, const LidarOptions& lidar, const ImuOptions& imu,
    const std::optional<ReceiveTimeRange>& range);

}  // namespace rvlio::bag_detail

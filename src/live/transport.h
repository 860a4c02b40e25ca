#pragma once
// Private (src/live): what `rvlio live` needs of a middleware. A transport
// receives the serialized LiDAR and IMU messages on threads of its own (one
// per topic, so that decoding a scan never delays an IMU sample) and
// publishes the outputs; publishing is thread-safe. Two transports:
// ROS 1 through roscpp (ros1_transport.cpp) and ROS 2 conventions on Cyclone
// DDS (dds_transport.cpp).
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/formats/live_options.h"
#include "rvlio/formats/live_source.h"
#include "rvlio/formats/nav_messages.h"
#include "rvlio/formats/pointcloud2.h"

namespace rvlio::live_detail {

// One received message: its bytes and its type as the transport names it
// (ROS 1 "sensor_msgs/Imu", ROS 2 "sensor_msgs/msg/Imu").
using MessageCallback =
    std::function<void(const uint8_t* data, size_t size, const std::string& type)>;

// The topics published, under live.topic_namespace.
struct OutputTopics {
  std::string odometry, odometry_imu, cloud, path, map, status, tf = "/tf";
  explicit OutputTopics(const std::string& ns)
      : odometry(ns + "/odometry"),
        odometry_imu(ns + "/odometry_imu"),
        cloud(ns + "/cloud_registered"),
        path(ns + "/path"),
        map(ns + "/map"),
        status(ns + "/status") {}
};

enum class CloudTopic { kRegisteredScan, kMap };
enum class OdometryTopic { kScanRate, kImuRate };

class Transport {
 public:
  virtual ~Transport() = default;
  virtual WireEncoding encoding() const = 0;
  // Where the messages come from, for messages ("ROS 1 master http://...").
  virtual std::string origin() const = 0;
  // Receives `topic` (any type) on a thread of its own; at most `depth`
  // messages wait for it (the oldest go first).
  virtual Status Subscribe(const std::string& topic, int depth, MessageCallback callback) = 0;
  virtual Status Advertise(const OutputTopics& topics) = 0;

  virtual void Publish(OdometryTopic which, const OdometryMessage& msg) = 0;
  virtual void PublishTf(const TransformMessage& msg) = 0;
  // x y z intensity float32 points (PointCloud2 with those four fields).
  virtual void Publish(CloudTopic which, const PointCloud2View& cloud,
                       const std::string& frame_id) = 0;
  virtual void Publish(const PathMessage& msg) = 0;
  virtual void Publish(const DiagnosticMessage& msg) = 0;
  // Stops the receiving threads (no callback runs after it returns).
  virtual void Shutdown() = 0;
  // Gives what was published the time to leave before the process ends
  // (at most about half a second).
  virtual void Flush() = 0;
};

// ROS 1: the master from ROS_MASTER_URI, answering within
// live.connect_timeout; InvalidInput (one line) when it is unset or does not
// answer. `stopped` is polled while waiting: true gives a null transport.
StatusOr<std::unique_ptr<Transport>> ConnectRos1(const LiveOptions& live, const std::string& node_name,
                                                 const std::function<bool()>& stopped);
// ROS 2 on Cyclone DDS, domain live.ros2_domain_id (-1: $ROS_DOMAIN_ID, else 0).
StatusOr<std::unique_ptr<Transport>> ConnectRos2(const LiveOptions& live);

}  // namespace rvlio::live_detail

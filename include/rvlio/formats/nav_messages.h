#pragma once
// The contents of the messages `rvlio live` publishes, independent of the
// wire (docs/live.md "Topics"): nav_msgs/Odometry, geometry_msgs/
// TransformStamped (in a tf2_msgs/TFMessage), nav_msgs/Path and
// diagnostic_msgs/DiagnosticArray with one DiagnosticStatus. The ROS 2
// encoders are in cdr.h; the ROS 1 transport fills roscpp's message classes.
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "rvlio/common/time.h"

namespace rvlio {

struct PoseMessage {
  std::array<double, 3> position{};                      // m
  std::array<double, 4> orientation_xyzw{0.0, 0.0, 0.0, 1.0};
};

// nav_msgs/Odometry: pose in frame_id, twist in child_frame_id.
struct OdometryMessage {
  TimeNs stamp_ns = 0;
  std::string frame_id, child_frame_id;
  PoseMessage pose;
  std::array<double, 36> pose_covariance{};  // row-major [x y z rx ry rz]
  std::array<double, 3> linear_velocity{};   // m/s, child frame
  std::array<double, 3> angular_velocity{};  // rad/s, child frame
  std::array<double, 36> twist_covariance{};
};

// geometry_msgs/TransformStamped.
struct TransformMessage {
  TimeNs stamp_ns = 0;
  std::string frame_id, child_frame_id;
  std::array<double, 3> translation{};
  std::array<double, 4> rotation_xyzw{0.0, 0.0, 0.0, 1.0};
};

// nav_msgs/Path (every pose stamped in frame_id).
struct PathMessage {
  TimeNs stamp_ns = 0;
  std::string frame_id;
  std::vector<std::pair<TimeNs, PoseMessage>> poses;
};

// diagnostic_msgs/DiagnosticArray with one DiagnosticStatus.
struct DiagnosticMessage {
  TimeNs stamp_ns = 0;
  uint8_t level = 0;  // 0 OK, 1 WARN, 2 ERROR, 3 STALE
  std::string name, message, hardware_id;
  std::vector<std::pair<std::string, std::string>> values;
};

}  // namespace rvlio

#pragma once
// Private (src/formats only): sensor_msgs/PointCloud2 and sensor_msgs/Imu parsed
// from their ROS1 wire bytes in place (ros1_wire.h), as the ROS 2 readers
// parse CDR: no message object, no zero-filled copy of the cloud's data.
#include <array>
#include <cstdint>
#include <string>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"
#include "rvlio/formats/pointcloud2.h"

namespace rvlio::bag_detail {

// The ROS1 names of the two types.
inline constexpr const char* kPointCloud2Type = "sensor_msgs/PointCloud2";
inline constexpr const char* kImuType = "sensor_msgs/Imu";

// The md5 sums ROS1 bags carry for the two types (the connection header's
// md5sum): a message under another md5 has another layout.
inline constexpr const char* kPointCloud2Md5 = "1158d486dd51d683ce2f1be655c3c181";
inline constexpr const char* kImuMd5 = "6a62c6daae103f4ff57a132d6f95cec2";

// A view into `data` (valid while those bytes live) whose topic is `topic`;
// `where` names the topic and bag in errors.
StatusOr<PointCloud2View> ParseRos1PointCloud2(const uint8_t* data, size_t size,
                                               const std::string& topic, const std::string& where);

// The fields of sensor_msgs/Imu that the estimators read.
struct Ros1Imu {
  TimeNs header_stamp_ns = 0;
  std::array<double, 3> angular_velocity{};     // rad/s
  std::array<double, 3> linear_acceleration{};  // m/s^2 (or g, per imu.accel_unit)
};
StatusOr<Ros1Imu> ParseRos1Imu(const uint8_t* data, size_t size, const std::string& where);

}  // namespace rvlio::bag_detail

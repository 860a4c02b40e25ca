#pragma once
// The LiDAR's pose in the IMU frame, T_imu_lidar: configuration section
// `extrinsics` (a fixed value, or the prior of its online estimate).
#include <array>

#include <Eigen/Geometry>

#include "rvlio/common/options.h"
#include "rvlio/math/pose.h"

namespace rvlio {

// LiDAR pose in the IMU frame.
struct ExtrinsicsOptions {
  std::array<double, 3> translation = {0.0, 0.0, 0.0};       // m, t_imu_lidar
  std::array<double, 4> rotation_xyzw = {0.0, 0.0, 0.0, 1.0};  // R_imu_lidar as a quaternion

  template <class V>
  void Visit(V& v) {
    v.Field("translation", translation, Spec().Unit("m").Range(-10.0, 10.0).Help("t_imu_lidar"));
    v.Field("rotation_xyzw", rotation_xyzw, Spec().Range(-1.0, 1.0).Help("R_imu_lidar quaternion x y z w"));
  }
};

struct ExtrinsicsSection {
  ExtrinsicsOptions imu_T_lidar;
  template <class V>
  void Visit(V& v) { v.Section("imu_T_lidar", imu_T_lidar); }
  Status Validate() {
    Status s = ValidateFields(*this, "extrinsics");
    if (!s.ok()) return s;
    const auto& q = imu_T_lidar.rotation_xyzw;
    const double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    if (n2 < 0.98 || n2 > 1.02)
      return Status::InvalidInput("extrinsics.imu_T_lidar.rotation_xyzw is not a unit quaternion");
    return s;
  }
};

// T_imu_lidar of the configuration (LiDAR pose in the IMU frame).
inline Pose3 ImuTLidar(const ExtrinsicsSection& extrinsics) {
  const auto& e = extrinsics.imu_T_lidar;
  return Pose3(Eigen::Quaterniond(e.rotation_xyzw[3], e.rotation_xyzw[0], e.rotation_xyzw[1],
                                  e.rotation_xyzw[2]),
               Eigen::Vector3d(e.translation[0], e.translation[1], e.translation[2]));
}

}  // namespace rvlio

#pragma once
// Motion compensation (deskew): every point is moved to the LiDAR frame at
// the scan end time using the IMU poses recorded while propagating across the
// scan (backward propagation, FAST-LIO2 structure).
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/types.h"
#include "rvlio/math/pose.h"

namespace rvlio {

// The IMU state at one propagation step, with the (bias-corrected) motion
// that holds until the next step.
struct ImuPoseSample {
  TimeNs t_ns = 0;
  Eigen::Matrix3d R_world_imu = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_world_imu = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_world_imu = Eigen::Vector3d::Zero();
  Eigen::Vector3d acc_world = Eigen::Vector3d::Zero();  // m/s^2, gravity included
  Eigen::Vector3d gyro_imu = Eigen::Vector3d::Zero();   // rad/s, bias removed
};

// Pose of the IMU at t_ns by constant-acceleration / constant-rate motion
// from the latest sample at or before t_ns (or the first one, backwards).
Pose3 InterpolateImuPose(const std::vector<ImuPoseSample>& samples, TimeNs t_ns);

// p_lidar_end[i] = T_lidar_end^-1 * T_world_lidar(t_i) * p_lidar[i], with
// T_world_lidar(t) = T_world_imu(t) * T_imu_lidar. `samples` must be sorted by
// time and end at (or after) the scan end `t_end_ns`.
void DeskewToScanEnd(const std::vector<ImuPoseSample>& samples, const Pose3& T_imu_lidar,
                     const std::vector<LidarPoint>& points, TimeNs t_end_ns,
                     std::vector<Eigen::Vector3d>* p_lidar_end);

}  // namespace rvlio

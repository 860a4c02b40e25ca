#pragma once
// Motion compensation (deskew): every point is moved to the LiDAR frame at
// the scan end time using the IMU poses over the scan (imu/pose_history.h:
// ImuPoseHistory::samples(), the same component for every backend).
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/types.h"
#include "rvlio/imu/pose_history.h"
#include "rvlio/math/pose.h"

namespace rvlio {

// p_lidar_end[i] = T_lidar_end^-1 * T_world_lidar(t_i) * p_lidar[i], with
// T_world_lidar(t) = T_world_imu(t) * T_imu_lidar. `samples` must be sorted by
// time and end at (or after) the scan end `t_end_ns`.
void DeskewToScanEnd(const std::vector<ImuPoseSample>& samples, const Pose3& T_imu_lidar,
                     const std::vector<LidarPoint>& points, TimeNs t_end_ns,
                     std::vector<Eigen::Vector3d>* p_lidar_end);

// The same for points kept apart from their times (p_lidar[i] at t_ns[i], as
// batch refinement stores them: 20 bytes a point instead of a LidarPoint's
// 32); the same result as for LidarPoints with these coordinates and times.
void DeskewToScanEnd(const std::vector<ImuPoseSample>& samples, const Pose3& T_imu_lidar,
                     const std::vector<Eigen::Vector3f>& p_lidar, const std::vector<TimeNs>& t_ns,
                     TimeNs t_end_ns, std::vector<Eigen::Vector3d>* p_lidar_end);

}  // namespace rvlio

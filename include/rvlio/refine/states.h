#pragma once
// Building blocks of batch refinement (refine/refine.h) that deal with the
// per-scan states: the initial trajectory, IMU slices, deskew with the
// current estimate and the gravity vector.
#include <array>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/time.h"
#include "rvlio/common/types.h"
#include "rvlio/math/pose.h"
#include "rvlio/factors/parameter_blocks.h"

namespace rvlio {

// The state of one scan at its end time, as the Ceres parameter blocks of the
// batch problem (factors/parameter_blocks.h layouts).
struct RefineState {
  TimeNs t_ns = 0;                  // scan end
  std::array<double, 7> pose{};     // PoseBlock: q_world_imu (x y z w), p_world_imu
  std::array<double, 9> speed_bias{};  // SpeedBiasBlock: v_world_imu, b_g, b_a

  Pose3 T_world_imu() const { return PoseBlock::FromArray(pose.data()).ToPose3(); }
  SpeedBiasBlock SpeedBias() const { return SpeedBiasBlock::FromArray(speed_bias.data()); }
};

// Central difference of the trajectory's positions over [t - h, t + h],
// clamped to the trajectory's span (m/s). Zero for a single pose.
Eigen::Vector3d FiniteDifferenceVelocity(const Trajectory& trajectory, TimeNs t_ns,
                                         TimeNs half_window_ns);

// The samples needed to integrate over [t0_ns, t1_ns]: those inside, plus the
// last one before and the first one after (for interpolation at the ends).
// `samples` sorted by time.
std::vector<ImuSample> SliceImu(const std::vector<ImuSample>& samples, TimeNs t0_ns,
                                TimeNs t1_ns);

// Deskew of one scan with the state at its end: the IMU is integrated
// backwards from the end state (pose, velocity, biases) to the earliest point
// time (ImuPoseHistory::Integrate, imu/pose_history.h), and every point is
// moved to the LiDAR frame at the scan end (lidar/deskew.h). `imu` must cover
// the scan (SliceImu).
void DeskewWithImu(const std::vector<ImuSample>& imu, const RefineState& end_state,
                   const Eigen::Vector3d& g_world, const Pose3& T_imu_lidar,
                   const std::vector<LidarPoint>& points, TimeNs t_start_ns,
                   std::vector<Eigen::Vector3d>* p_lidar_end);

// The same for points kept apart from their times (lidar/deskew.h).
void DeskewWithImu(const std::vector<ImuSample>& imu, const RefineState& end_state,
                   const Eigen::Vector3d& g_world, const Pose3& T_imu_lidar,
                   const std::vector<Eigen::Vector3f>& p_lidar, const std::vector<TimeNs>& t_ns,
                   TimeNs t_start_ns, std::vector<Eigen::Vector3d>* p_lidar_end);

// Rotation angle (deg) and translation (m) between two poses.
double RotationDifferenceDeg(const Pose3& a, const Pose3& b);
double TranslationDifference(const Pose3& a, const Pose3& b);

}  // namespace rvlio

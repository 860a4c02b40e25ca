#include "rvlio/refine/states.h"

#include <algorithm>
#include <cmath>

#include "rvlio/common/check.h"
#include "rvlio/imu/pose_history.h"
#include "rvlio/lidar/deskew.h"
#include "rvlio/math/pose_interpolation.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

Eigen::Vector3d PositionAt(const Trajectory& trajectory, TimeNs t_ns) {
  Pose3 T;
  const bool inside = InterpolatePose(trajectory, t_ns, &T);
  RVLIO_CHECK(inside);
  return T.t;
}

}  // namespace

Eigen::Vector3d FiniteDifferenceVelocity(const Trajectory& trajectory, TimeNs t_ns,
                                         TimeNs half_window_ns) {
  RVLIO_CHECK(!trajectory.empty() && half_window_ns > 0);
  const TimeNs t0 = std::max(trajectory.front().t_ns, t_ns - half_window_ns);
  const TimeNs t1 = std::min(trajectory.back().t_ns, t_ns + half_window_ns);
  if (t1 <= t0) return Eigen::Vector3d::Zero();
  return (PositionAt(trajectory, t1) - PositionAt(trajectory, t0)) / NsToSeconds(t1 - t0);
}

std::vector<ImuSample> SliceImu(const std::vector<ImuSample>& samples, TimeNs t0_ns,
                                TimeNs t1_ns) {
  const auto by_time = [](const ImuSample& s, TimeNs t) { return s.t_ns < t; };
  auto first = std::lower_bound(samples.begin(), samples.end(), t0_ns, by_time);
  if (first != samples.begin()) --first;
  auto last = std::lower_bound(samples.begin(), samples.end(), t1_ns, by_time);
  if (last != samples.end()) ++last;
  return std::vector<ImuSample>(first, last);
}

namespace {

// The IMU integrated backwards from the scan-end state (imu/pose_history.h).
ImuPoseHistory BackwardHistory(const std::vector<ImuSample>& imu, const RefineState& end_state,
                               const Eigen::Vector3d& g_world, TimeNs t_start_ns) {
  RVLIO_CHECK(!imu.empty());
  const SpeedBiasBlock sb = end_state.SpeedBias();
  const Pose3 T_end = end_state.T_world_imu();
  ImuKinematics end;
  end.t_ns = end_state.t_ns;
  end.R_world_imu = T_end.R;
  end.p_world_imu = T_end.t;
  end.v_world_imu = sb.v_world_imu;
  return ImuPoseHistory::Integrate(end, imu, std::min(t_start_ns, end_state.t_ns), sb.bg, sb.ba,
                                   g_world);
}

}  // namespace

void DeskewWithImu(const std::vector<ImuSample>& imu, const RefineState& end_state,
                   const Eigen::Vector3d& g_world, const Pose3& T_imu_lidar,
                   const std::vector<LidarPoint>& points, TimeNs t_start_ns,
                   std::vector<Eigen::Vector3d>* p_lidar_end) {
  const ImuPoseHistory history = BackwardHistory(imu, end_state, g_world, t_start_ns);
  DeskewToScanEnd(history.samples(), T_imu_lidar, points, end_state.t_ns, p_lidar_end);
}

void DeskewWithImu(const std::vector<ImuSample>& imu, const RefineState& end_state,
                   const Eigen::Vector3d& g_world, const Pose3& T_imu_lidar,
                   const std::vector<Eigen::Vector3f>& p_lidar, const std::vector<TimeNs>& t_ns,
                   TimeNs t_start_ns, std::vector<Eigen::Vector3d>* p_lidar_end) {
  const ImuPoseHistory history = BackwardHistory(imu, end_state, g_world, t_start_ns);
  DeskewToScanEnd(history.samples(), T_imu_lidar, p_lidar, t_ns, end_state.t_ns, p_lidar_end);
}

double RotationDifferenceDeg(const Pose3& a, const Pose3& b) {
  return so3::Log(a.R.transpose() * b.R).norm() * 180.0 / M_PI;
}

double TranslationDifference(const Pose3& a, const Pose3& b) { return (a.t - b.t).norm(); }

}  // namespace rvlio

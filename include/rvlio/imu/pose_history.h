#pragma once
// The IMU pose history of one interval: the poses that deskew
// (lidar/deskew.h) reads at every point time, and the newest state that
// prediction hands to the estimator. One component for the three backends,
// after GLIM's single IMU integration that serves both prediction and deskew:
//   - the IESKF appends the states of its own propagation (Append), each with
//     the measurement held until its next step (FAST-LIO2);
//   - the sliding-window smoother integrates forward from its newest state to
//     the scan end (Integrate; Newest() is the prediction);
//   - batch refine integrates backward from a scan-end state to the scan
//     start (Integrate with an earlier end time).
// Poses between the samples follow constant angular rate and world
// acceleration from the latest sample (PoseAt).
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/time.h"
#include "rvlio/common/types.h"
#include "rvlio/imu/integrator.h"
#include "rvlio/math/pose.h"

namespace rvlio {

// The IMU state at one knot, with the (bias-corrected) motion that holds
// until the next knot.
struct ImuPoseSample {
  TimeNs t_ns = 0;
  Eigen::Matrix3d R_world_imu = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_world_imu = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_world_imu = Eigen::Vector3d::Zero();
  Eigen::Vector3d acc_world = Eigen::Vector3d::Zero();  // m/s^2, gravity included
  Eigen::Vector3d gyro_imu = Eigen::Vector3d::Zero();   // rad/s, bias removed
};

// The pose dt_s (may be negative) after the sample's time by its constant
// angular rate and world acceleration.
Pose3 AdvanceImuPose(const ImuPoseSample& s, double dt_s);

// Pose of the IMU at t_ns by constant-acceleration / constant-rate motion
// from the latest sample at or before t_ns (or the first one, backwards).
// samples: non-empty, sorted by time.
Pose3 InterpolateImuPose(const std::vector<ImuPoseSample>& samples, TimeNs t_ns);

class ImuPoseHistory {
 public:
  // The knots of IntegrateTrajectory() (imu/integrator.h) from `start` over
  // `imu` to t_end_ns (later or earlier than start.t_ns), in increasing time.
  // Knot i carries the motion of the integration scheme up to knot i + 1:
  // rate (w_i + w_i+1)/2 - b_g and world acceleration
  // (R_i (a_i - b_a) + R_i+1 (a_i+1 - b_a))/2 + g, so PoseAt() reproduces
  // every integrated state exactly; the last knot holds its own signal.
  static ImuPoseHistory Integrate(const ImuKinematics& start, const std::vector<ImuSample>& imu,
                                  TimeNs t_end_ns, const Eigen::Vector3d& bg,
                                  const Eigen::Vector3d& ba, const Eigen::Vector3d& g_world);

  // Appends a propagated state (time not before the newest sample's).
  void Append(const ImuPoseSample& sample);
  void Clear() { samples_.clear(); }

  // The pose at t_ns (InterpolateImuPose). Not empty.
  Pose3 PoseAt(TimeNs t_ns) const { return InterpolateImuPose(samples_, t_ns); }
  // The newest state (e.g. the prediction at the scan end). Not empty.
  ImuKinematics Newest() const;

  const std::vector<ImuPoseSample>& samples() const { return samples_; }
  bool empty() const { return samples_.empty(); }

 private:
  std::vector<ImuPoseSample> samples_;  // sorted by time
};

}  // namespace rvlio

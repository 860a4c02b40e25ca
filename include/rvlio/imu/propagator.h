#pragma once
// The IMU state at IMU rate between two estimates: from the latest estimate
// (kinematics, biases, gravity), integrated over the IMU samples received
// since (IntegrateInterval, the estimators' own scheme). `rvlio live`
// publishes it as the IMU-rate odometry while the estimator works on a scan.
// Not thread-safe: the caller serializes SetEstimate and Add.
#include <deque>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/time.h"
#include "rvlio/common/types.h"
#include "rvlio/imu/integrator.h"

namespace rvlio {

// An estimator's state at state.t_ns.
struct ImuEstimate {
  ImuKinematics state;
  Eigen::Vector3d bg_imu = Eigen::Vector3d::Zero();  // rad/s
  Eigen::Vector3d ba_imu = Eigen::Vector3d::Zero();  // m/s^2
  Eigen::Vector3d g_world = Eigen::Vector3d(0.0, 0.0, -9.81);
};

class ImuPropagator {
 public:
  // Samples older than the newest one by more than keep_ns are forgotten
  // (an estimate older than what is kept starts from the oldest kept sample).
  explicit ImuPropagator(TimeNs keep_ns) : keep_ns_(keep_ns) {}

  // A new estimate: the current state becomes it, carried forward over the
  // kept samples after its time. An estimate older than the current one's is ignored.
  void SetEstimate(const ImuEstimate& estimate);
  // A new sample (time increasing; an older or repeated one is ignored):
  // the state at its time once an estimate exists, else nothing.
  std::optional<ImuKinematics> Add(const ImuSample& sample);

  bool has_estimate() const { return estimate_.has_value(); }
  // The kept samples, oldest first.
  const std::deque<ImuSample>& samples() const { return samples_; }
  // The samples that cover [t0_ns, t1_ns]: from the last one at or before t0
  // to the first one at or after t1 (those inside when the span is not covered).
  std::vector<ImuSample> Covering(TimeNs t0_ns, TimeNs t1_ns) const;

 private:
  void Step(const ImuSample& sample);

  TimeNs keep_ns_;
  std::deque<ImuSample> samples_;
  std::optional<ImuEstimate> estimate_;
  ImuKinematics current_;  // the estimate carried to the newest sample used
  ImuSample signal_;       // the IMU signal at current_.t_ns
};

}  // namespace rvlio

#pragma once
// The trajectory at IMU rate between a backend's states (`output.imu_trajectory`,
// trajectory_imu.tum, docs/outputs.md): a pose at every IMU sample's stamp
// from the first state to the last, and at every state's stamp.
//
// Between two consecutive states a (at t_a) and b (at t_b) the IMU is
// integrated forward from a with a's velocity, biases and gravity
// (Integrate, the scheme of ImuPropagator and the estimators' IMU
// prediction: imu/integrator.h); the poses at the samples strictly inside
// (t_a, t_b) are then joined to b in one of two ways:
//   kPropagate  as integrated: the filter's view (IESKF). At t_b the pose
//               is b's (the update), so the trajectory steps there by the
//               update's correction. These are the poses ImuPropagator
//               (`rvlio live`'s IMU-rate odometry) gives once a's estimate is
//               set before the samples after t_a arrive.
//   kSpread     the end mismatch spread linearly in time (smoother, refine:
//               states jointly estimated with the IMU between them): with
//               s = (t - t_a) / (t_b - t_a) and the integrated pose
//               (R_int, p_int),
//                 p(t) = p_int(t) + s (p_b - p_int(t_b))
//                 R(t) = Exp(s Log(R_b R_int(t_b)^T)) R_int(t)   (world frame)
//               so the trajectory is continuous and passes through b.
// Either way the pose at every state's stamp is the state's own.
#include <deque>
#include <optional>
#include <vector>

#include "rvlio/common/types.h"
#include "rvlio/imu/integrator.h"
#include "rvlio/imu/propagator.h"

namespace rvlio {

enum class ImuRateJoin {
  kPropagate,  // forward integration from each state, the next state's pose at its stamp
  kSpread,     // forward integration with the end mismatch spread linearly in time
};

// The states over (a.state.t_ns, b.state.t_ns]: one at each sample strictly
// inside, then b's. `samples`: sorted, covering the interval (the last one at
// or before t_a to the first one at or after t_b; the signal is held beyond
// them, as the integrator does); may be empty (then b's state only).
// b.state.t_ns must be later than a.state.t_ns.
std::vector<ImuKinematics> ImuRateBetween(const ImuEstimate& a, const ImuEstimate& b,
                                          const std::vector<ImuSample>& samples, ImuRateJoin join);

// Builds the trajectory as samples and states arrive (a run's results come
// after the IMU samples covering them): the poses up to each state are
// appended when it arrives, and only the samples from the newest state's on
// are kept.
class ImuRateTrajectory {
 public:
  explicit ImuRateTrajectory(ImuRateJoin join) : join_(join) {}

  // A sample; one not after the newest, or not finite, is ignored.
  void AddImu(const ImuSample& sample);
  // The next state; one not after the newest is ignored. Appends the poses
  // over (previous state, this state] (this state's pose only for the first).
  void AddEstimate(const ImuEstimate& estimate);

  const Trajectory& poses() const { return poses_; }
  Trajectory TakePoses() { return std::move(poses_); }

 private:
  ImuRateJoin join_;
  std::deque<ImuSample> samples_;  // from the last one at or before last_'s time
  std::optional<ImuEstimate> last_;
  Trajectory poses_;
};

// The whole trajectory of `states` (sorted by time) over `samples` (sorted).
Trajectory ImuRatePoses(const std::vector<ImuEstimate>& states,
                        const std::vector<ImuSample>& samples, ImuRateJoin join);

}  // namespace rvlio

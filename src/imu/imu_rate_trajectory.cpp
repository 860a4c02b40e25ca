#include "rvlio/imu/imu_rate_trajectory.h"

#include "rvlio/common/check.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

StampedPose ToStampedPose(const ImuKinematics& x) {
  StampedPose p;
  p.t_ns = x.t_ns;
  p.p_world_imu = x.p_world_imu;
  p.q_world_imu = Eigen::Quaterniond(x.R_world_imu).normalized();
  return p;
}

// The integrated states moved so that the last one lands on `end`: the
// position and (world-frame) rotation mismatch at the end, in proportion to
// the time since `t0_ns`.
void SpreadEndMismatch(TimeNs t0_ns, const ImuKinematics& end, std::vector<ImuKinematics>* states) {
  const ImuKinematics& integrated = states->back();
  const Eigen::Vector3d dp = end.p_world_imu - integrated.p_world_imu;
  const Eigen::Vector3d dtheta = so3::Log(end.R_world_imu * integrated.R_world_imu.transpose());
  const double span = static_cast<double>(end.t_ns - t0_ns);
  for (ImuKinematics& x : *states) {
    const double s = static_cast<double>(x.t_ns - t0_ns) / span;
    x.p_world_imu += s * dp;
    x.R_world_imu = so3::Exp(s * dtheta) * x.R_world_imu;
  }
}

}  // namespace

std::vector<ImuKinematics> ImuRateBetween(const ImuEstimate& a, const ImuEstimate& b,
                                          const std::vector<ImuSample>& samples, ImuRateJoin join) {
  RVLIO_CHECK(b.state.t_ns > a.state.t_ns);
  if (samples.empty()) return {b.state};
  std::vector<ImuKinematics> states =
      IntegrateTrajectory(a.state, samples, b.state.t_ns, a.bg_imu, a.ba_imu, a.g_world);
  states.erase(states.begin());  // a itself
  if (join == ImuRateJoin::kSpread) SpreadEndMismatch(a.state.t_ns, b.state, &states);
  states.back() = b.state;
  return states;
}

void ImuRateTrajectory::AddImu(const ImuSample& sample) {
  if (!sample.acc_imu.allFinite() || !sample.gyro_imu.allFinite()) return;
  if (!samples_.empty() && sample.t_ns <= samples_.back().t_ns) return;
  samples_.push_back(sample);
}

void ImuRateTrajectory::AddEstimate(const ImuEstimate& estimate) {
  const TimeNs t_ns = estimate.state.t_ns;
  if (last_ && t_ns <= last_->state.t_ns) return;
  if (!last_) {
    poses_.push_back(ToStampedPose(estimate.state));
  } else {
    std::vector<ImuSample> covering;  // the last one at or before last_, to the first at or after t
    for (const ImuSample& s : samples_) {
      covering.push_back(s);
      if (s.t_ns >= t_ns) break;
    }
    for (const ImuKinematics& x : ImuRateBetween(*last_, estimate, covering, join_))
      poses_.push_back(ToStampedPose(x));
  }
  last_ = estimate;
  while (samples_.size() >= 2 && samples_[1].t_ns <= t_ns) samples_.pop_front();
}

Trajectory ImuRatePoses(const std::vector<ImuEstimate>& states,
                        const std::vector<ImuSample>& samples, ImuRateJoin join) {
  ImuRateTrajectory out(join);
  size_t next = 0;
  for (const ImuEstimate& e : states) {
    // the samples up to the first one at or after the state
    for (; next < samples.size() && (next == 0 || samples[next - 1].t_ns < e.state.t_ns); ++next)
      out.AddImu(samples[next]);
    out.AddEstimate(e);
  }
  return out.TakePoses();
}

}  // namespace rvlio

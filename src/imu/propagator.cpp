#include "rvlio/imu/propagator.h"

namespace rvlio {

void ImuPropagator::Step(const ImuSample& sample) {
  current_ = IntegrateInterval(current_, signal_, sample, estimate_->bg_imu, estimate_->ba_imu,
                               estimate_->g_world);
  signal_ = sample;
}

void ImuPropagator::SetEstimate(const ImuEstimate& estimate) {
  if (estimate_ && estimate.state.t_ns < estimate_->state.t_ns) return;
  estimate_ = estimate;
  current_ = estimate.state;
  if (samples_.empty()) {
    signal_ = ImuSample();
    signal_.t_ns = current_.t_ns;
    // at rest until a sample says otherwise
    signal_.acc_imu = estimate.ba_imu - current_.R_world_imu.transpose() * estimate.g_world;
    signal_.gyro_imu = estimate.bg_imu;
    return;
  }
  const std::vector<ImuSample> kept(samples_.begin(), samples_.end());
  signal_ = InterpolateImu(kept, current_.t_ns);
  signal_.t_ns = current_.t_ns;
  for (const ImuSample& s : samples_)
    if (s.t_ns > current_.t_ns) Step(s);
}

std::optional<ImuKinematics> ImuPropagator::Add(const ImuSample& sample) {
  if (!samples_.empty() && sample.t_ns <= samples_.back().t_ns) return std::nullopt;
  samples_.push_back(sample);
  while (samples_.size() > 2 && samples_.front().t_ns < sample.t_ns - keep_ns_)
    samples_.pop_front();
  if (!estimate_) return std::nullopt;
  if (sample.t_ns > current_.t_ns) Step(sample);
  return current_;
}

std::vector<ImuSample> ImuPropagator::Covering(TimeNs t0_ns, TimeNs t1_ns) const {
  std::vector<ImuSample> out;
  for (const ImuSample& s : samples_) {
    if (!out.empty() && s.t_ns <= t0_ns) out.clear();  // keep the last one at or before t0
    out.push_back(s);
    if (s.t_ns >= t1_ns) break;
  }
  return out;
}

}  // namespace rvlio

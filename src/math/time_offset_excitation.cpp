#include "rvlio/math/time_offset_excitation.h"

#include <algorithm>
#include <cmath>

namespace rvlio {
namespace {

// Root of the summed per-axis variances of n vectors.
template <class Get>
double Spread(const std::deque<Get>& window, Eigen::Vector3d (*value)(const Get&)) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Get& s : window) mean += value(s);
  mean /= static_cast<double>(window.size());
  double sum_sq = 0.0;
  for (const Get& s : window) sum_sq += (value(s) - mean).squaredNorm();
  return std::sqrt(sum_sq / static_cast<double>(window.size()));
}

}  // namespace

void TimeOffsetExcitation::CountScan(TimeNs t_ns, const Eigen::Vector3d& gyro_imu,
                                     const Eigen::Vector3d& v_world) {
  window_.push_back({t_ns, gyro_imu, v_world});
  while (window_.front().t_ns < t_ns - kWindowNs) window_.pop_front();
  const double rate = Spread<Sample>(window_, [](const Sample& s) { return s.gyro_imu; });
  const double velocity = Spread<Sample>(window_, [](const Sample& s) { return s.v_world; });
  max_rate_spread_ = std::max(max_rate_spread_, rate);
  max_velocity_spread_ = std::max(max_velocity_spread_, velocity);
  const bool excited_now = rate >= kMinRateSpread || velocity >= kMinVelocitySpread;
  if (excited_now && last_t_ns_ >= 0) excited_s_ += NsToSeconds(t_ns - last_t_ns_);
  if (first_t_ns_ < 0) first_t_ns_ = t_ns;
  last_t_ns_ = t_ns;
}

}  // namespace rvlio

#include "rvlio/odometry/divergence.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "rvlio/common/median.h"
#include "rvlio/refine/refine.h"

namespace rvlio {

const char* DivergenceKindName(DivergenceKind k) {
  switch (k) {
    case DivergenceKind::kSpeed: return "speed";
    case DivergenceKind::kJump: return "jump";
    case DivergenceKind::kNis: return "nis";
    case DivergenceKind::kResidual: return "residual";
    case DivergenceKind::kInliers: return "inliers";
    case DivergenceKind::kGravity: return "gravity";
    case DivergenceKind::kRotation: return "rotation";
  }
  return "unknown";
}

std::string DivergenceKindNames(uint8_t mask) {
  std::string names;
  for (int k = 0; k < kNumDivergenceKinds; ++k) {
    if ((mask & (1u << k)) == 0) continue;
    if (!names.empty()) names += '+';
    names += DivergenceKindName(static_cast<DivergenceKind>(k));
  }
  return names;
}

std::string DivergenceEvent::Describe() const {
  char text[256];
  switch (kind) {
    case DivergenceKind::kSpeed:
      std::snprintf(text, sizeof(text), "speed %.1f m/s > divergence.max_speed %g m/s", value,
                    threshold);
      break;
    case DivergenceKind::kJump:
      std::snprintf(text, sizeof(text), "position jump %.2f m in one scan > %.2f m allowed", value,
                    threshold);
      break;
    case DivergenceKind::kNis:
      std::snprintf(text, sizeof(text),
                    "innovation NIS per constraint %.1f (window mean) > divergence.max_nis %g",
                    value, threshold);
      break;
    case DivergenceKind::kResidual:
      std::snprintf(text, sizeof(text),
                    "median point-to-plane residual %.4f m (window median) > %.4f m", value,
                    threshold);
      break;
    case DivergenceKind::kInliers:
      std::snprintf(text, sizeof(text),
                    "constraints per point %.2f (window mean) < divergence.min_inlier_fraction %g",
                    value, threshold);
      break;
    case DivergenceKind::kGravity:
      std::snprintf(text, sizeof(text),
                    "mean measured specific force %.2f m/s^2 (window) where imu.gravity is %g m/s^2: "
                    "check imu.accel_unit",
                    value, threshold);
      break;
    case DivergenceKind::kRotation:
      std::snprintf(text, sizeof(text),
                    "the scans turn %.2f deg per scan against the gyro (window mean) > "
                    "divergence.max_lidar_rotation_deg %g: check the extrinsic rotation, or "
                    "the LiDAR-IMU time offset (rvlio calibrate-time)",
                    value, threshold);
      break;
  }
  return text;
}

double DivergenceMonitor::Window::Mean() const {
  double sum = 0.0;
  for (double v : values) sum += v;
  return values.empty() ? 0.0 : sum / static_cast<double>(values.size());
}

double DivergenceMonitor::Window::Median() const {
  return UpperMedian(std::vector<double>(values.begin(), values.end()));
}

DivergenceMonitor::DivergenceMonitor(const DivergenceOptions& options, double lidar_noise_m,
                                     double gravity_mps2)
    : options_(options), lidar_noise_m_(lidar_noise_m), gravity_mps2_(gravity_mps2) {}

void DivergenceMonitor::Push(Window* w, double value) const {
  w->values.push_back(value);
  while (static_cast<int>(w->values.size()) > options_.window_scans) w->values.pop_front();
}

bool DivergenceMonitor::Full(const Window& w) const {
  return static_cast<int>(w.values.size()) >= options_.window_scans;
}

void DivergenceMonitor::Trip(DivergenceKind k, TimeNs t_ns, double value, double threshold,
                             uint8_t* mask) {
  const int i = static_cast<int>(k);
  *mask |= static_cast<uint8_t>(1u << i);
  clear_scans_[i] = 0;
  if (active_[i]) return;  // the episode goes on: reported at its start only
  active_[i] = true;
  ++report_.episodes[i];
  report_.events.push_back({k, t_ns, value, threshold});
  if (!report_.detected) report_.first_t_ns = t_ns;
  report_.detected = true;
}

// A kind's episode ends after a window of scans without it.
void DivergenceMonitor::EndEpisodes(uint8_t mask) {
  for (int i = 0; i < kNumDivergenceKinds; ++i) {
    if (!active_[i] || (mask & (1u << i)) != 0) continue;
    if (++clear_scans_[i] >= options_.window_scans) active_[i] = false;
  }
}

// Residuals by motion up to (and with) the scan of the first divergence.
void DivergenceMonitor::CountMotionResidual(const HealthSample& s, bool detected_before) {
  if (detected_before || !s.associated || !std::isfinite(s.health.residual_median_m)) return;
  const double speed = s.v_world_imu.norm();
  if (speed < DivergenceReport::kRestSpeed) {
    rest_sum_m_ += s.health.residual_median_m;
    ++rest_scans_;
  } else if (speed > DivergenceReport::kMovingSpeed) {
    moving_sum_m_ += s.health.residual_median_m;
    ++moving_scans_;
  }
  if (rest_scans_ > 0) report_.residual_at_rest_m = rest_sum_m_ / rest_scans_;
  if (moving_scans_ > 0) report_.residual_moving_m = moving_sum_m_ / moving_scans_;
  report_.clock_suspect = rest_scans_ >= DivergenceReport::kClockSuspectMinScans &&
                          moving_scans_ >= DivergenceReport::kClockSuspectMinScans &&
                          report_.residual_moving_m >
                              DivergenceReport::kClockSuspectRatio * report_.residual_at_rest_m;
}

uint8_t DivergenceMonitor::Check(const HealthSample& s) {
  uint8_t mask = 0;
  if (!options_.enabled) return mask;
  CountMotionResidual(s, report_.detected);
  const double speed = s.v_world_imu.norm();
  if (!std::isfinite(speed) || speed > options_.max_speed)
    Trip(DivergenceKind::kSpeed, s.t_ns, speed, options_.max_speed, &mask);
  if (have_previous_ && s.t_ns > previous_.t_ns) {
    const double dt_s = NsToSeconds(s.t_ns - previous_.t_ns);
    const double allowed =
        std::max(speed, previous_.v_world_imu.norm()) * dt_s + options_.jump_slack;
    const double step = (s.p_world_imu - previous_.p_world_imu).norm();
    if (!std::isfinite(step) || step > allowed)
      Trip(DivergenceKind::kJump, s.t_ns, step, allowed, &mask);
  }
  if (std::isfinite(s.health.nis_per_dof)) {
    Push(&nis_, s.health.nis_per_dof);
    const double mean = nis_.Mean();
    if (Full(nis_) && mean > options_.max_nis)
      Trip(DivergenceKind::kNis, s.t_ns, mean, options_.max_nis, &mask);
  }
  if (std::isfinite(s.health.residual_median_m)) {
    Push(&residual_, s.health.residual_median_m);
    const double median = residual_.Median();
    const double limit = options_.max_residual_ratio * lidar_noise_m_;
    if (Full(residual_) && median > limit)
      Trip(DivergenceKind::kResidual, s.t_ns, median, limit, &mask);
  }
  if (s.associated && s.points > 0) {
    Push(&inliers_, static_cast<double>(s.constraints) / s.points);
    const double mean = inliers_.Mean();
    if (Full(inliers_) && mean < options_.min_inlier_fraction)
      Trip(DivergenceKind::kInliers, s.t_ns, mean, options_.min_inlier_fraction, &mask);
  }
  if (std::isfinite(s.specific_force_mps2) && s.specific_force_mps2 > 0.0) {
    Push(&specific_force_, s.specific_force_mps2);
    const double mean = specific_force_.Mean();
    if (Full(specific_force_) &&
        std::abs(mean / gravity_mps2_ - 1.0) > options_.max_gravity_error)
      Trip(DivergenceKind::kGravity, s.t_ns, mean, gravity_mps2_, &mask);
  }
  if (std::isfinite(s.health.lidar_rotation_deg)) {
    Push(&lidar_rotation_, s.health.lidar_rotation_deg);
    const double mean = lidar_rotation_.Mean();
    if (Full(lidar_rotation_) && mean > options_.max_lidar_rotation_deg)
      Trip(DivergenceKind::kRotation, s.t_ns, mean, options_.max_lidar_rotation_deg, &mask);
  }
  EndEpisodes(mask);
  if (mask != 0) ++report_.scans_flagged;
  previous_ = s;
  have_previous_ = true;
  return mask;
}

DivergenceReport CheckRefineResult(const RefineResult& result, const DivergenceOptions& options,
                                   double lidar_noise_m, double gravity_mps2) {
  DivergenceMonitor monitor(options, lidar_noise_m, gravity_mps2);
  const RefineRound* last = result.rounds.empty() ? nullptr : &result.rounds.back();
  for (size_t i = 0; i < result.trajectory.size(); ++i) {
    HealthSample s;
    s.t_ns = result.trajectory[i].t_ns;
    s.p_world_imu = result.trajectory[i].p_world_imu;
    if (i < result.v_world_imu.size()) s.v_world_imu = result.v_world_imu[i];
    if (last != nullptr && last->points > 0) {
      constexpr int kPerMillion = 1000000;  // the round's ratio in parts per million
      s.associated = true;
      s.points = kPerMillion;
      s.constraints = static_cast<int>(std::lround(
          kPerMillion * static_cast<double>(last->constraints) / static_cast<double>(last->points)));
    }
    monitor.Check(s);
  }
  return monitor.report();
}

}  // namespace rvlio

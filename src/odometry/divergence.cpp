#include "rvlio/odometry/divergence.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "rvlio/common/median.h"

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

namespace {

// What an inconsistency explained by a clock offset adds to its description.
std::string ClockExplanation(const DivergenceEvent& e) {
  char text[384];
  std::snprintf(text, sizeof(text),
                "; a LiDAR-IMU clock offset of %+.1f ms explains %.0f %% of the scans' rotation "
                "against the gyro (the estimate follows the scans, late; not divergence): add "
                "%.4f s to lidar.time_offset, or run with --set lidar.estimate_time_offset=true "
                "(`rvlio calibrate-time` checks it)",
                1e3 * e.clock_offset_s, 100.0 * e.clock_explained, e.clock_offset_s);
  return text;
}

}  // namespace

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
                    "divergence.max_lidar_rotation_deg %g%s",
                    value, threshold,
                    !lost     ? ""
                    : still ? ", while the gyro showed no rotation (where neither the "
                              "extrinsic rotation nor the clocks show): the scans disagree "
                              "with the map"
                              : ", and no LiDAR-IMU clock offset explains it: check the "
                                "extrinsic rotation");
      break;
  }
  if (!lost) return text + ClockExplanation(*this);
  return still && kind != DivergenceKind::kRotation
             ? text + std::string(", while the gyro showed no rotation")
             : text;
}

ClockFit FitClockOffset(const std::deque<RotationSample>& samples) {
  ClockFit f;
  f.scans = static_cast<int>(samples.size());
  double rr = 0.0, rw = 0.0, ww = 0.0;
  for (const RotationSample& s : samples) {
    rr += s.lidar_rotation_imu.squaredNorm();
    rw += s.lidar_rotation_imu.dot(s.rate_change_imu);
    ww += s.rate_change_imu.squaredNorm();
  }
  if (!(ww > 0.0) || !(rr > 0.0)) return f;
  f.offset_s = rw / ww;
  // sum |r - tau w|^2 = rr - 2 tau rw + tau^2 ww = rr - rw^2 / ww at the optimum.
  f.explained = rw * rw / (ww * rr);
  return f;
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
                                     double gravity_mps2, double max_clock_offset_s)
    : options_(options),
      lidar_noise_m_(lidar_noise_m),
      gravity_mps2_(gravity_mps2),
      max_clock_offset_s_(max_clock_offset_s) {}

void DivergenceMonitor::Push(Window* w, double value) const {
  w->values.push_back(value);
  while (static_cast<int>(w->values.size()) > options_.window_scans) w->values.pop_front();
}

bool DivergenceMonitor::Full(const Window& w) const {
  return static_cast<int>(w.values.size()) >= options_.window_scans;
}

DivergenceEvent DivergenceMonitor::Judge(DivergenceKind k, TimeNs t_ns, double value,
                                         double threshold) const {
  DivergenceEvent e{k, t_ns, value, threshold};
  e.still = still_.Mean() >= DivergenceReport::kStillShare;
  if (e.still || (k != DivergenceKind::kNis && k != DivergenceKind::kRotation)) return e;
  const ClockFit fit = FitClockOffset(rotations_);
  if (2 * fit.scans < options_.window_scans || !(fit.explained >= options_.min_clock_explained) ||
      !(std::abs(fit.offset_s) <= max_clock_offset_s_))
    return e;
  e.lost = false;
  e.clock_offset_s = fit.offset_s;
  e.clock_explained = fit.explained;
  return e;
}

void DivergenceMonitor::Trip(DivergenceKind k, TimeNs t_ns, double value, double threshold,
                             uint8_t* mask) {
  const int i = static_cast<int>(k);
  clear_scans_[i] = 0;
  if (!active_[i]) {  // a new episode, judged at its start; reported once
    active_[i] = true;
    const DivergenceEvent e = Judge(k, t_ns, value, threshold);
    active_lost_[i] = e.lost;
    report_.events.push_back(e);
    if (e.lost) {
      ++report_.episodes[i];
      if (!report_.detected) report_.first_t_ns = t_ns;
      report_.detected = true;
    } else {
      ++report_.inconsistencies;
      report_.clock_offset_s = e.clock_offset_s;
      report_.clock_suspect = true;
    }
  }
  *mask |= static_cast<uint8_t>(1u << i);
}

// The clock fit's window: scans with a LiDAR-only rotation and a previous scan.
void DivergenceMonitor::PushRotation(const HealthSample& s) {
  if (!have_previous_ || !s.health.lidar_rotation_imu.allFinite()) return;
  rotations_.push_back({s.health.lidar_rotation_imu, s.mean_gyro_imu - previous_.mean_gyro_imu});
  while (static_cast<int>(rotations_.size()) > options_.window_scans) rotations_.pop_front();
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
  residual_clock_suspect_ = rest_scans_ >= DivergenceReport::kClockSuspectMinScans &&
                            moving_scans_ >= DivergenceReport::kClockSuspectMinScans &&
                            report_.residual_moving_m >
                                DivergenceReport::kClockSuspectRatio * report_.residual_at_rest_m;
  report_.clock_suspect = residual_clock_suspect_ || report_.inconsistencies > 0;
}

uint8_t DivergenceMonitor::Check(const HealthSample& s) {
  uint8_t mask = 0;
  if (!options_.enabled) return mask;
  CountMotionResidual(s, report_.detected);
  PushRotation(s);
  const double speed = s.v_world_imu.norm();
  Push(&still_, s.mean_gyro_imu.norm() < DivergenceReport::kStillRate ? 1.0 : 0.0);
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
  if (s.health.lidar_rotation_imu.allFinite()) {
    Push(&lidar_rotation_, s.health.lidar_rotation_imu.norm() * 180.0 / M_PI);
    const double mean = lidar_rotation_.Mean();
    if (Full(lidar_rotation_) && mean > options_.max_lidar_rotation_deg)
      Trip(DivergenceKind::kRotation, s.t_ns, mean, options_.max_lidar_rotation_deg, &mask);
  }
  EndEpisodes(mask);
  for (int i = 0; i < kNumDivergenceKinds; ++i)  // the kinds tripped as divergence
    if (!active_lost_[i]) mask &= static_cast<uint8_t>(~(1u << i));
  if (mask != 0) ++report_.scans_flagged;
  previous_ = s;
  have_previous_ = true;
  return mask;
}

}  // namespace rvlio

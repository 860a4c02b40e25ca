#pragma once
// Divergence monitor: checks every scan result of an estimator (IESKF,
// smoother, refine) for signs that the estimate no longer tracks the sensor,
// so that no run ends in silent garbage. No I/O: the caller reports.
//
// Checks (each an option of section `divergence`; thresholds and how they
// were chosen: docs/robustness.md):
//   speed     |v_world_imu| above max_speed.
//   jump      the position step between two scans beyond what the velocity
//             and the scan period allow (max(|v|) dt + jump_slack).
//   nis       window mean of the normalized innovation squared (IESKF:
//             z^T (H P H^T + R)^-1 z / n of the point-to-plane residuals at
//             the prediction) above max_nis.
//   residual  window median of the per-scan median |r| after the update
//             above max_residual_ratio * constraints.lidar_noise.
//   inliers   window mean of constraints / downsampled points below
//             min_inlier_fraction (the scans stop matching the map).
//   rotation  window mean of the rotation the LiDAR alone asks of the
//             IESKF's prediction (first iteration, position held) above
//             max_lidar_rotation_deg: the gyro and the scans disagree about
//             how the platform turns (a wrong extrinsic rotation such as an
//             upside-down mount turns every turn around for the LiDAR).
//   gravity   window mean of the per-scan mean specific force |f| off
//             imu.gravity by more than max_gravity_error (relative): over
//             seconds any vehicle's mean |f| is close to g, so a wrong
//             accelerometer unit (g read as m/s^2, or the reverse) shows
//             even when the LiDAR keeps the pose on track.
// A windowed check only trips once its window of `window_scans` scans is
// full. A kind's episode starts when it trips and ends after `window_scans`
// consecutive scans where it does not: the caller warns once per episode.
//
// Lost or inconsistent. speed, jump, residual, inliers and gravity are
// evidence that the estimate is lost (or meaningless): their episodes are
// divergence. nis and rotation measure the filter's consistency; an
// inconsistency the scans themselves explain by a LiDAR-IMU clock offset
// (FitClockOffset below: the rotation the scans ask of the gyro is tau times
// the change of the rotation rate, with min_clock_explained of it explained
// and |tau| within lidar.time_offset_max) leaves the estimate with the scans,
// only late: such an episode is an inconsistency (DivergenceEvent::lost
// false, a warning naming tau), not divergence. Any other nis or rotation
// episode is divergence. An episode is judged when it starts.
#include <array>
#include <cstdint>
#include <deque>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/options.h"
#include "rvlio/common/types.h"
#include "rvlio/lidar/options.h"
#include "rvlio/odometry/divergence_options.h"

namespace rvlio {

enum class DivergenceKind : int { kSpeed = 0, kJump, kNis, kResidual, kInliers, kGravity, kRotation };
constexpr int kNumDivergenceKinds = 7;
const char* DivergenceKindName(DivergenceKind k);
// The kinds set in a ScanHealth::divergence_mask, "speed+nis"; "" for none.
std::string DivergenceKindNames(uint8_t mask);

// What the monitor reads of one scan (ScanResult::health carries it).
struct ScanHealth {
  static constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();
  double nis_per_dof = kUnknown;        // NaN: not computed (smoother, refine, no update)
  double residual_median_m = kUnknown;  // median |r| after the update; NaN: no update
  double residual_rms_m = kUnknown;
  // IESKF: the LiDAR-only rotation step at the prediction (rad, IMU frame;
  // IeskfUpdateResult::lidar_rotation_imu); NaN: not computed.
  Eigen::Vector3d lidar_rotation_imu = Eigen::Vector3d::Constant(kUnknown);
  uint8_t divergence_mask = 0;          // bit k set: DivergenceKind k tripped on this scan
};

// The start of one episode of one kind: when, what was seen, the limit, and
// whether it is divergence (lost) or an inconsistency a clock offset explains.
struct DivergenceEvent {
  DivergenceKind kind = DivergenceKind::kSpeed;
  TimeNs t_ns = 0;
  double value = 0.0;
  double threshold = 0.0;
  bool lost = true;
  // The gyro showed no rotation (mean rate below DivergenceReport::kStillRate
  // on kStillShare of the window up to the event): neither a wrong extrinsic
  // rotation nor a clock offset shows there; with a reference map, the start
  // or the map is what the scans disagree with.
  bool still = false;
  // Inconsistency (lost false): the clock offset the window's rotations
  // suggest (s, to add to lidar.time_offset) and the share they explain.
  double clock_offset_s = std::numeric_limits<double>::quiet_NaN();
  double clock_explained = std::numeric_limits<double>::quiet_NaN();
  std::string Describe() const;  // "speed 73.2 m/s > 50 m/s"
};

// One scan as the clock fit sees it: the rotation the scans alone ask of the
// prediction and the change of the mean gyro rate since the previous scan
// (rad, rad/s; IMU frame).
struct RotationSample {
  Eigen::Vector3d lidar_rotation_imu = Eigen::Vector3d::Zero();
  Eigen::Vector3d rate_change_imu = Eigen::Vector3d::Zero();
};

// A LiDAR clock late by tau against the IMU (t_imu = t_lidar + tau) shows
// each scan the attitude the gyro reaches tau later: between two scans the
// scans turn by the gyro's turn plus about tau times the change of the rate,
// and with the filter following the scans that excess is the LiDAR-only
// rotation of the next scan. The least-squares tau over the samples, and the
// share of sum |rotation|^2 it explains (1 - sum |r - tau dw|^2 / sum |r|^2);
// offset NaN and explained 0 without rate change. (The offline estimate from
// the scans' own rotation rates is `rvlio calibrate-time`, clock_check.h.)
struct ClockFit {
  int scans = 0;
  double offset_s = std::numeric_limits<double>::quiet_NaN();
  double explained = 0.0;
};
ClockFit FitClockOffset(const std::deque<RotationSample>& samples);

struct DivergenceReport {
  bool detected = false;                                // a lost episode: divergence
  TimeNs first_t_ns = -1;                               // of the first lost episode
  std::array<int64_t, kNumDivergenceKinds> episodes{};  // lost episodes per kind
  int64_t scans_flagged = 0;                            // scans in a lost episode
  std::vector<DivergenceEvent> events;                  // every episode start (lost or not), in time order
  int64_t inconsistencies = 0;                          // episodes with lost false
  // The clock offset the last inconsistency suggested (s, to add to
  // lidar.time_offset); NaN without one.
  double clock_offset_s = std::numeric_limits<double>::quiet_NaN();
  // The scans up to the first divergence, split by motion: mean of the
  // per-scan median residuals at rest (speed < kRestSpeed) and moving
  // (speed > kMovingSpeed); NaN without such scans. A LiDAR-IMU clock offset
  // leaves the scans at rest exact and grows the residuals with the motion:
  // clock_suspect when moving > kClockSuspectRatio x at rest (both with at
  // least kClockSuspectMinScans scans; wrong extrinsics look the same), or
  // when a clock offset explained an inconsistency (clock_offset_s).
  double residual_at_rest_m = std::numeric_limits<double>::quiet_NaN();
  double residual_moving_m = std::numeric_limits<double>::quiet_NaN();
  bool clock_suspect = false;
  static constexpr double kRestSpeed = 0.05;          // m/s
  static constexpr double kStillRate = 0.01;          // rad/s, DivergenceEvent::still
  // The share of the window's scans below kStillRate for "still": an
  // upside-down mount trips one second into a slow start with 70 % of its
  // window below the rate (6 s tunnel, seed 2), a wrong start at rest 100 %.
  static constexpr double kStillShare = 0.9;
  static constexpr double kMovingSpeed = 0.3;         // m/s
  static constexpr double kClockSuspectRatio = 2.5;
  static constexpr int kClockSuspectMinScans = 5;
};

// One scan as the monitor sees it.
struct HealthSample {
  TimeNs t_ns = 0;
  Eigen::Vector3d p_world_imu = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_world_imu = Eigen::Vector3d::Zero();
  bool associated = false;  // the scan was matched against the map (not the first scan)
  int points = 0;         // downsampled points
  int constraints = 0;
  double specific_force_mps2 = ScanHealth::kUnknown;  // |mean IMU acceleration| over the scan
  Eigen::Vector3d mean_gyro_imu = Eigen::Vector3d::Zero();  // mean IMU rotation rate over the scan, rad/s
  ScanHealth health;
};

class DivergenceMonitor {
 public:
  // max_clock_offset_s: lidar.time_offset_max, the largest clock offset
  // that explains an inconsistency.
  DivergenceMonitor(const DivergenceOptions& options, double lidar_noise_m, double gravity_mps2,
                    double max_clock_offset_s = LidarOptions().time_offset_max);

  // Checks one scan; returns the mask of kinds tripped on it as divergence
  // (ScanHealth; an inconsistency's kind is not in it).
  // Scans must come in time order.
  uint8_t Check(const HealthSample& s);
  const DivergenceReport& report() const { return report_; }

 private:
  struct Window {
    std::deque<double> values;
    double Mean() const;
    double Median() const;
  };
  void Push(Window* w, double value) const;
  bool Full(const Window& w) const;
  void Trip(DivergenceKind k, TimeNs t_ns, double value, double threshold, uint8_t* mask);
  // An episode starting now: lost, or explained by a clock offset (nis, rotation).
  DivergenceEvent Judge(DivergenceKind k, TimeNs t_ns, double value, double threshold) const;
  void PushRotation(const HealthSample& s);
  void EndEpisodes(uint8_t mask);
  void CountMotionResidual(const HealthSample& s, bool detected_before);

  DivergenceOptions options_;
  double lidar_noise_m_;
  double gravity_mps2_;
  double max_clock_offset_s_;
  DivergenceReport report_;
  bool have_previous_ = false;
  HealthSample previous_;
  Window nis_, residual_, inliers_, specific_force_, lidar_rotation_;
  std::deque<RotationSample> rotations_;  // the last window_scans scans with a LiDAR-only rotation
  double rest_sum_m_ = 0.0, moving_sum_m_ = 0.0;  // CountMotionResidual
  int rest_scans_ = 0, moving_scans_ = 0;
  std::array<bool, kNumDivergenceKinds> active_{};
  std::array<bool, kNumDivergenceKinds> active_lost_{};  // the active episode is divergence
  bool residual_clock_suspect_ = false;  // CountMotionResidual's finding
  Window still_;  // 1 for a scan whose gyro rate is below kStillRate, else 0
  std::array<int, kNumDivergenceKinds> clear_scans_{};
};

}  // namespace rvlio

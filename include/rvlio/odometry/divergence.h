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
#include <array>
#include <cstdint>
#include <deque>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/options.h"
#include "rvlio/common/types.h"

namespace rvlio {

// Defaults against what was measured (docs/robustness.md: full-length
// simulated presets, several seeds, IESKF and smoother; wrong configurations
// on a 15 s tunnel): the largest window NIS on normal runs was 3.1 (hall),
// wrong configurations 19 to 110; residual median 0.028 m normal (smoother,
// hall), 0.048 to 0.151 m wrong; inlier fraction >= 0.31 normal; gravity
// error <= 0.065 normal, 0.9 / 8.8 for a wrong unit; speeds 2 m/s, steps
// 0.18 m normal.
struct DivergenceOptions {
  bool enabled = true;
  double max_speed = 50.0;             // m/s; a fast car stays below, a diverged filter passes it
  double jump_slack = 1.0;             // m, added to max(|v|) * dt (normal: 0.03 m beyond v dt)
  int window_scans = 20;               // scans of the windowed checks (2 s at 10 Hz)
  double max_nis = 10.0;               // mean NIS per degree of freedom over the window (3x normal)
  double max_residual_ratio = 2.5;     // window median of median |r| / lidar_noise (0.075 m; 2.7x normal)
  double min_inlier_fraction = 0.15;   // window mean of constraints / points (normal >= 0.31)
  double max_gravity_error = 0.5;      // relative error of the window mean |f| vs imu.gravity
  double max_lidar_rotation_deg = 0.15;  // deg, window mean of the LiDAR-only rotation step (IESKF; normal < 0.1)

  template <class V>
  void Visit(V& v) {
    v.Field("enabled", enabled, Spec().Help("check every scan for divergence"));
    v.Field("max_speed", max_speed, Spec().Unit("m/s").Positive()
        .Help("an estimated speed above this is divergence"));
    v.Field("jump_slack", jump_slack, Spec().Unit("m").Positive()
        .Help("a position step between scans larger than max(|v|) * dt + this is divergence"));
    v.Field("window_scans", window_scans, Spec().Range(2, 10000)
        .Help("scans over which nis, residual and inlier statistics are averaged"));
    v.Field("max_nis", max_nis, Spec().Positive()
        .Help("IESKF: window mean of the normalized innovation squared per constraint above this is divergence"));
    v.Field("max_residual_ratio", max_residual_ratio, Spec().Positive()
        .Help("window median of the median |point-to-plane residual| after the update, in units of constraints.lidar_noise, above this is divergence"));
    v.Field("min_inlier_fraction", min_inlier_fraction, Spec().Range(0.0, 1.0)
        .Help("window mean of constraints per downsampled point below this is divergence (0: off)"));
    v.Field("max_gravity_error", max_gravity_error, Spec().Positive()
        .Help("window mean of the measured specific force off imu.gravity by more than this fraction is divergence (wrong imu.accel_unit)"));
    v.Field("max_lidar_rotation_deg", max_lidar_rotation_deg, Spec().Unit("deg").Positive()
        .Help("IESKF: window mean of the rotation the scans alone ask of the gyro's prediction above this is divergence (wrong extrinsic rotation)"));
  }
  Status Validate() { return ValidateFields(*this, "divergence"); }
};

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
  double lidar_rotation_deg = kUnknown;  // IESKF: LiDAR-only rotation step at the prediction
  uint8_t divergence_mask = 0;          // bit k set: DivergenceKind k tripped on this scan
};

// The start of one episode of one kind: when, what was seen, the limit.
struct DivergenceEvent {
  DivergenceKind kind = DivergenceKind::kSpeed;
  TimeNs t_ns = 0;
  double value = 0.0;
  double threshold = 0.0;
  std::string Describe() const;  // "speed 73.2 m/s > 50 m/s"
};

struct DivergenceReport {
  bool detected = false;
  TimeNs first_t_ns = -1;
  std::array<int64_t, kNumDivergenceKinds> episodes{};  // per kind
  int64_t scans_flagged = 0;                            // scans with any kind tripped
  std::vector<DivergenceEvent> events;                  // every episode start, in time order
  // The scans up to the first divergence, split by motion: mean of the
  // per-scan median residuals at rest (speed < kRestSpeed) and moving
  // (speed > kMovingSpeed); NaN without such scans. A LiDAR-IMU clock offset
  // leaves the scans at rest exact and grows the residuals with the motion:
  // clock_suspect when moving > kClockSuspectRatio x at rest (both with at
  // least kClockSuspectMinScans scans). Wrong extrinsics look the same.
  double residual_at_rest_m = std::numeric_limits<double>::quiet_NaN();
  double residual_moving_m = std::numeric_limits<double>::quiet_NaN();
  bool clock_suspect = false;
  static constexpr double kRestSpeed = 0.05;          // m/s
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
  ScanHealth health;
};

class DivergenceMonitor {
 public:
  DivergenceMonitor(const DivergenceOptions& options, double lidar_noise_m, double gravity_mps2);

  // Checks one scan; returns the mask of kinds tripped on it (ScanHealth).
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
  void EndEpisodes(uint8_t mask);
  void CountMotionResidual(const HealthSample& s, bool detected_before);

  DivergenceOptions options_;
  double lidar_noise_m_;
  double gravity_mps2_;
  DivergenceReport report_;
  bool have_previous_ = false;
  HealthSample previous_;
  Window nis_, residual_, inliers_, specific_force_, lidar_rotation_;
  double rest_sum_m_ = 0.0, moving_sum_m_ = 0.0;  // CountMotionResidual
  int rest_scans_ = 0, moving_scans_ = 0;
  std::array<bool, kNumDivergenceKinds> active_{};
  std::array<int, kNumDivergenceKinds> clear_scans_{};
};

struct RefineResult;

// `refine`'s result through the same checks, scan by scan in time order:
// speed and jump from the refined poses and velocities, and the inlier
// fraction of the last round (constraints / points over all scans; refine
// keeps no per-scan figure). NIS and residuals are the IESKF's and the
// smoother's online figures and are not checked here.
DivergenceReport CheckRefineResult(const RefineResult& result, const DivergenceOptions& options,
                                   double lidar_noise_m, double gravity_mps2);

}  // namespace rvlio

#pragma once
// The options of the divergence monitor (section `divergence`; the monitor:
// odometry/divergence.h). Options only, so that odometry/options.h holds the
// configuration without the monitor.
#include "rvlio/common/options.h"
#include "rvlio/common/status.h"

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
  double min_clock_explained = 0.3;    // share of the window's LiDAR-only rotation a clock offset must explain (measured: clock >= 0.47, wrong extrinsic <= 0.12)

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
    v.Field("min_clock_explained", min_clock_explained, Spec().Range(0.0, 1.0)
        .Help("IESKF: a nis or rotation episode whose window of LiDAR-only rotations a LiDAR-IMU clock offset explains to this share (offset within lidar.time_offset_max) is an inconsistency (a warning naming the offset), not divergence; 1: never"));
  }
  Status Validate() { return ValidateFields(*this, "divergence"); }
};

}  // namespace rvlio

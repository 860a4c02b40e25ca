#pragma once
// Excitation of an online-estimated LiDAR-IMU time offset, shared by the
// IESKF and the smoother backends.
//
// A time offset dt moves the LiDAR's pose along the motion: rotation by
// w dt, position by v dt. A constant (w, v) makes that a constant pose
// offset, which the map absorbs (the map is built with the same offset), so
// only a change of the motion reveals dt: rotation-rate changes (angular
// acceleration) or velocity changes (acceleration). The measure: over the
// scans of the last kWindowNs, the spread (root of the summed per-axis
// variances) of the bias-corrected angular rate and of the world velocity.
// A scan is excited when the rate spread reaches kMinRateSpread or the
// velocity spread reaches kMinVelocitySpread (at 2 ms these move the LiDAR
// by 0.1 mrad / 0.4 mm, the scale a scan resolves); the estimate counts as
// excited once kMinExcitedSeconds of scans were. Whether it is trustworthy
// also needs the estimator's 1-sigma (lidar.time_offset_excited_std).
#include <deque>

#include <Eigen/Core>

#include "rvlio/common/time.h"

namespace rvlio {

class TimeOffsetExcitation {
 public:
  static constexpr TimeNs kWindowNs = 2000000000;  // 2 s
  static constexpr double kMinRateSpread = 0.05;     // rad/s
  static constexpr double kMinVelocitySpread = 0.2;  // m/s
  static constexpr double kMinExcitedSeconds = 5.0;

  // One processed scan at t_ns with the motion held there.
  void CountScan(TimeNs t_ns, const Eigen::Vector3d& gyro_imu, const Eigen::Vector3d& v_world);

  bool excited() const { return excited_s_ >= kMinExcitedSeconds; }
  double excited_seconds() const { return excited_s_; }
  // Seconds from the first scan counted to the last.
  double counted_seconds() const {
    return first_t_ns_ >= 0 ? NsToSeconds(last_t_ns_ - first_t_ns_) : 0.0;
  }
  double max_rate_spread() const { return max_rate_spread_; }          // rad/s
  double max_velocity_spread() const { return max_velocity_spread_; }  // m/s

 private:
  struct Sample {
    TimeNs t_ns;
    Eigen::Vector3d gyro_imu, v_world;
  };
  std::deque<Sample> window_;
  TimeNs first_t_ns_ = -1, last_t_ns_ = -1;
  double excited_s_ = 0.0;
  double max_rate_spread_ = 0.0, max_velocity_spread_ = 0.0;
};

}  // namespace rvlio

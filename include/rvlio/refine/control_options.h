#pragma once
// Options of the survey ties (docs/control.md): control points and check
// points of a control file (`refine --control`, section `control`) and GNSS
// fixes of the recording (section `gnss`). Plain option structs: the core
// uses them through PositionTie (refine/control.h); reading the control file
// and the NavSatFix messages is the I/O layer's.
#include <array>
#include <string>
#include <utility>

#include "rvlio/common/options.h"

namespace rvlio {

// The robust kernel of a position tie: the loss of its whitened residual
// norm s (in sigmas), with width c: huber rho = s^2 (s <= c), 2 c s - c^2;
// cauchy rho = c^2 log(1 + s^2 / c^2); none: s^2.
enum class TieKernel { kNone, kHuber, kCauchy };

template <>
struct EnumNames<TieKernel> {
  static constexpr std::pair<TieKernel, const char*> kNames[] = {
      {TieKernel::kNone, "none"}, {TieKernel::kHuber, "huber"}, {TieKernel::kCauchy, "cauchy"}};
};

struct ControlOptions {
  double sigma_m = 0.005;          // a mark's standard deviation per axis (the file's sigma_m wins)
  double min_rest_s = 2.0;         // shortest rest period that can be a stop-and-go landing
  double rest_window_s = 0.5;      // IMU window of the stillness test
  double rest_gyro_std = 0.01;     // rad/s: stillness when the gyro's std is below (norm over axes)
  double rest_accel_std = 0.1;     // m/s^2: ... and the accelerometer's std is below
  double rest_sigma_v = 0.001;     // m/s: zero-velocity factor on a mark's rest (0: none)
  // The IMU origin relative to the mark, in the body frame at rest (m).
  std::array<double, 3> lever_arm = {0.0, 0.0, 0.0};
  double max_distance_m = 5.0;     // a mark farther from the aligned trajectory: refused (a typo)
  double min_spread_m = 1.0;       // the control points' least horizontal extent to fix the heading
  double tilt_sigma_deg = 0.5;     // prior of the alignment's roll/pitch at gravity's (0: held)
  TieKernel kernel = TieKernel::kHuber;
  double kernel_sigmas = 3.0;      // kernel width in sigmas
  double warn_sigmas = 5.0;        // a control point's residual beyond this many sigmas: a warning
  double target_radius_m = 0.3;    // a scan saw a target when one of its points is this close
  int target_max_scans = 10;       // scans that tie one target (the closest to it)

  template <class V>
  void Visit(V& v) {
    v.Field("sigma_m", sigma_m,
            Spec().Unit("m").Range(1e-4, 10.0).Help(
                "standard deviation per axis of a control point (the file's sigma_m column wins)"));
    v.Field("min_rest_s", min_rest_s,
            Spec().Unit("s").Range(0.1, 3600.0).Help(
                "shortest rest period found from the IMU that counts as a stop-and-go landing"));
    v.Field("rest_window_s", rest_window_s,
            Spec().Unit("s").Range(0.05, 10.0).Help("IMU window of the stillness test"));
    v.Field("rest_gyro_std", rest_gyro_std,
            Spec().Unit("rad/s").Range(1e-5, 1.0).Help(
                "still when the gyro's standard deviation over the window (norm over the axes) is "
                "below this"));
    v.Field("rest_accel_std", rest_accel_std,
            Spec().Unit("m/s^2").Range(1e-4, 10.0).Help(
                "... and the accelerometer's is below this"));
    v.Field("rest_sigma_v", rest_sigma_v,
            Spec().Unit("m/s").Range(0.0, 10.0).Help(
                "refine holds the velocity of every state inside a stop-and-go mark's rest at zero "
                "with this sigma (0: no such factor)"));
    v.Field("lever_arm", lever_arm,
            Spec().Unit("m").Range(-100.0, 100.0).Help(
                "the IMU origin relative to a stop-and-go mark, in the body frame at rest"));
    v.Field("max_distance_m", max_distance_m,
            Spec().Unit("m").Range(0.01, 1e6).Help(
                "a mark farther than this from the trajectory after the alignment is refused (a "
                "typo in its coordinates)"));
    v.Field("min_spread_m", min_spread_m,
            Spec().Unit("m").Range(0.01, 1e6).Help(
                "the control points (and GNSS fixes) must span at least this horizontally to fix "
                "the heading"));
    v.Field("tilt_sigma_deg", tilt_sigma_deg,
            Spec().Unit("deg").Range(0.0, 10.0).Help(
                "the alignment refines roll and pitch with this prior at gravity's (a static "
                "alignment reads the accelerometer bias as a tilt, |b| / g); 0: roll and pitch "
                "from gravity alone"));
    v.Field("kernel", kernel,
            Spec().Choices(EnumChoices<TieKernel>()).Help("robust kernel of a control point"));
    v.Field("kernel_sigmas", kernel_sigmas,
            Spec().Range(0.1, 1000.0).Help("width of that kernel in sigmas"));
    v.Field("warn_sigmas", warn_sigmas,
            Spec().Range(0.1, 1e6).Help(
                "a control point whose residual after the solve exceeds this many sigmas is named "
                "in a warning"));
    v.Field("target_radius_m", target_radius_m,
            Spec().Unit("m").Range(0.01, 10.0).Help(
                "a scan saw a wall target when one of its points lies this close to the target "
                "(map_x, map_y, map_z) at the --init pose"));
    v.Field("target_max_scans", target_max_scans,
            Spec().Range(1, 1000).Help("scans that tie one target: those closest to it"));
  }
  Status Validate() { return ValidateFields(*this, "control"); }
};

struct GnssOptions {
  std::string topic;               // sensor_msgs/NavSatFix topic ("" = none)
  std::array<double, 3> lever_arm = {0.0, 0.0, 0.0};  // antenna in the IMU frame, m
  double sigma_m = 0.03;           // per axis, when the message has no covariance (or not used)
  bool use_covariance = true;      // the message's position_covariance when it has one
  TieKernel kernel = TieKernel::kCauchy;
  double kernel_sigmas = 2.0;
  double max_distance_m = 10.0;    // farther from the aligned trajectory: an outlier, left out

  template <class V>
  void Visit(V& v) {
    v.Field("topic", topic,
            Spec().Help("sensor_msgs/NavSatFix topic of the recording (empty: no GNSS); refine "
                        "ties the trajectory to its fixes"));
    v.Field("lever_arm", lever_arm,
            Spec().Unit("m").Range(-100.0, 100.0).Help("the antenna's position in the IMU frame"));
    v.Field("sigma_m", sigma_m,
            Spec().Unit("m").Range(1e-4, 100.0).Help(
                "standard deviation per axis of a fix without a covariance"));
    v.Field("use_covariance", use_covariance,
            Spec().Help("use the message's position_covariance when its type is not unknown"));
    v.Field("kernel", kernel,
            Spec().Choices(EnumChoices<TieKernel>()).Help(
                "robust kernel of a fix (multipath near portals)"));
    v.Field("kernel_sigmas", kernel_sigmas,
            Spec().Range(0.1, 1000.0).Help("width of that kernel in sigmas"));
    v.Field("max_distance_m", max_distance_m,
            Spec().Unit("m").Range(0.01, 1e6).Help(
                "a fix farther than this from the trajectory after the alignment is an outlier "
                "and left out (counted)"));
  }
  Status Validate() { return ValidateFields(*this, "gnss"); }
};

}  // namespace rvlio

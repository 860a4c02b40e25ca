#pragma once
// Rest periods of a recording from its IMU alone (stop-and-go control
// marks, docs/control.md "Stop-and-go").
//
// A sample is still when, over the window of `window_s` centred on it, the
// standard deviation of the gyro (the root of the summed per-axis variances)
// is below `gyro_std` and that of the accelerometer below `accel_std`. A
// rest period is a run of consecutive still samples (no IMU gap longer than
// kRestMaxGapS inside) lasting at least `min_duration_s`; it runs from the
// first to the last still sample.
//
// Stillness is a low variance: a device that moves at a constant velocity
// without vibration looks the same to an IMU. A flying drone's rotors make
// its IMU signal vibrate, a hand-held device sways; on the floor, a pole or
// a tripod both are quiet.
#include <vector>

#include "rvlio/common/time.h"
#include "rvlio/common/types.h"

namespace rvlio {

constexpr double kRestMaxGapS = 0.1;  // an IMU gap longer than this ends a rest period

struct RestDetectorOptions {
  double window_s = 0.5;        // s
  double gyro_std = 0.01;       // rad/s
  double accel_std = 0.1;       // m/s^2
  double min_duration_s = 2.0;  // s
};

struct RestPeriod {
  TimeNs t_begin_ns = 0;
  TimeNs t_end_ns = 0;
  TimeNs MidNs() const { return t_begin_ns + (t_end_ns - t_begin_ns) / 2; }
  double DurationS() const { return NsToSeconds(t_end_ns - t_begin_ns); }
};

// `imu` sorted by time. In time order.
std::vector<RestPeriod> FindRestPeriods(const std::vector<ImuSample>& imu,
                                        const RestDetectorOptions& options);

}  // namespace rvlio

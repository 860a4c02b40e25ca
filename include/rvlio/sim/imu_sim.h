#pragma once
// IMU measurements along a FlightTrajectory:
//   gyro_imu = w_imu + b_g + n_g,   acc_imu = R_world_imu^T (a_world - g_world) + b_a + n_a
// with g_world = (0, 0, -gravity), discrete white noise n ~ N(0, sigma_c^2 rate),
// biases starting at the configured constants and walking as
// b_{k+1} = b_k + sigma_rw sqrt(dt) N(0, 1), and an optional motor vibration
// (sinusoid at vibration_frequency on both signals).
#include <cstdint>

#include <Eigen/Core>

#include "rvlio/common/types.h"
#include "rvlio/sim/options.h"
#include "rvlio/sim/random.h"
#include "rvlio/sim/trajectory.h"

namespace rvlio::sim {

class ImuSimulator {
 public:
  ImuSimulator(const FlightTrajectory& trajectory, const SimImuOptions& options, uint64_t seed);

  // Time of sample k: t0 + round(k * 1e9 / rate).
  TimeNs SampleTime(int64_t k) const;
  TimeNs NextTime() const { return SampleTime(next_); }
  // The next sample in time order (sample 0 at t0).
  ImuSample Next();

  // True biases used for the sample most recently returned.
  const Eigen::Vector3d& gyro_bias() const { return bg_; }
  const Eigen::Vector3d& accel_bias() const { return ba_; }
  // Noise-free measurement at any time (no bias, noise or vibration).
  static ImuSample Ideal(const FlightTrajectory& trajectory, TimeNs t_ns);

 private:
  const FlightTrajectory& trajectory_;
  SimImuOptions options_;
  Rng rng_;
  int64_t next_ = 0;
  Eigen::Vector3d bg_, ba_;
  Eigen::Vector3d bg_next_, ba_next_;
  double vibration_phase_[6] = {0, 0, 0, 0, 0, 0};
};

}  // namespace rvlio::sim

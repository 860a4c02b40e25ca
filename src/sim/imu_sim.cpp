#include "rvlio/sim/imu_sim.h"

#include <cmath>

namespace rvlio::sim {

namespace {
// Relative vibration amplitude per axis (x, y, z): mostly along the thrust.
constexpr double kVibrationAxis[3] = {0.5, 0.5, 1.0};

Eigen::Vector3d NormalVector(Rng& rng, double stddev) {
  // Draw in a fixed order (x, y, z) for determinism.
  const double x = rng.Normal(stddev), y = rng.Normal(stddev), z = rng.Normal(stddev);
  return Eigen::Vector3d(x, y, z);
}
}  // namespace

ImuSimulator::ImuSimulator(const FlightTrajectory& trajectory, const SimImuOptions& options,
                           uint64_t seed)
    : trajectory_(trajectory), options_(options), rng_(Rng::Stream(seed, 3)) {
  bg_next_ = Eigen::Vector3d(options.gyro_bias[0], options.gyro_bias[1], options.gyro_bias[2]);
  ba_next_ = Eigen::Vector3d(options.accel_bias[0], options.accel_bias[1], options.accel_bias[2]);
  bg_ = bg_next_;
  ba_ = ba_next_;
  for (double& p : vibration_phase_) p = rng_.Uniform(0.0, 2.0 * M_PI);
}

TimeNs ImuSimulator::SampleTime(int64_t k) const {
  const double offset_ns = static_cast<double>(k) * 1e9 / options_.rate;
  return trajectory_.t0_ns() + static_cast<TimeNs>(std::llround(offset_ns));
}

ImuSample ImuSimulator::Ideal(const FlightTrajectory& trajectory, TimeNs t_ns) {
  const TruthState s = trajectory.At(t_ns);
  const Eigen::Vector3d g_world(0.0, 0.0, -trajectory.gravity());
  ImuSample m;
  m.t_ns = t_ns;
  m.gyro_imu = s.w_imu;
  m.acc_imu = s.T_world_imu.R.transpose() * (s.a_world_imu - g_world);
  return m;
}

ImuSample ImuSimulator::Next() {
  ImuSample m = Ideal(trajectory_, SampleTime(next_));
  bg_ = bg_next_;
  ba_ = ba_next_;
  const double dt = 1.0 / options_.rate;
  const double sqrt_rate = std::sqrt(options_.rate);
  m.gyro_imu += bg_ + NormalVector(rng_, options_.gyro_noise_density * sqrt_rate);
  m.acc_imu += ba_ + NormalVector(rng_, options_.accel_noise_density * sqrt_rate);
  // Stop-and-go flights: the motors stand still while landed.
  const bool still = trajectory_.stop_and_go() && trajectory_.Landed(NsToSeconds(m.t_ns - trajectory_.t0_ns()));
  if ((options_.vibration_accel > 0.0 || options_.vibration_gyro > 0.0) && !still) {
    const double arg =
        2.0 * M_PI * options_.vibration_frequency * NsToSeconds(m.t_ns - trajectory_.t0_ns());
    for (int i = 0; i < 3; ++i) {
      m.acc_imu[i] +=
          options_.vibration_accel * kVibrationAxis[i] * std::sin(arg + vibration_phase_[i]);
      m.gyro_imu[i] +=
          options_.vibration_gyro * kVibrationAxis[2 - i] * std::sin(arg + vibration_phase_[3 + i]);
    }
  }
  bg_next_ = bg_ + NormalVector(rng_, options_.gyro_bias_random_walk * std::sqrt(dt));
  ba_next_ = ba_ + NormalVector(rng_, options_.accel_bias_random_walk * std::sqrt(dt));
  ++next_;
  return m;
}

}  // namespace rvlio::sim

#pragma once
// IMU noise: continuous-time densities (ImuOptions) -> discrete covariances.
//
// Convention (the Kalibr / "IMU noise model" one):
// - White measurement noise with density sigma (gyro: rad/s/sqrt(Hz), accel:
//   m/s^2/sqrt(Hz)) seen in one sample that represents an interval dt has
//   per-sample variance  sigma^2 / dt  (std sigma / sqrt(dt)). Integrated over
//   dt (times dt^2) it contributes sigma^2 dt, so the result does not depend on
//   the sample rate.
// - A bias random walk with density sigma_b (gyro: rad/s^2/sqrt(Hz), accel:
//   m/s^3/sqrt(Hz)) changes the bias over dt by a zero-mean increment with
//   variance  sigma_b^2 * dt.
// The 12-dim noise vector is ordered [n_g, n_a, n_bg, n_ba] (offsets below).
#include <Eigen/Core>

#include "rvlio/imu/options.h"

namespace rvlio {

using Matrix12d = Eigen::Matrix<double, 12, 12>;

struct ImuNoise {
  static constexpr int kGyro = 0;       // gyro white noise
  static constexpr int kAccel = 3;      // accel white noise
  static constexpr int kGyroBias = 6;   // gyro bias random walk
  static constexpr int kAccelBias = 9;  // accel bias random walk
  static constexpr int kDim = 12;

  double gyro_noise_density = 0.0;      // rad/s/sqrt(Hz)
  double accel_noise_density = 0.0;     // m/s^2/sqrt(Hz)
  double gyro_bias_random_walk = 0.0;   // rad/s^2/sqrt(Hz)
  double accel_bias_random_walk = 0.0;  // m/s^3/sqrt(Hz)

  static ImuNoise FromOptions(const ImuOptions& options);

  // Per-sample measurement covariances for a sample interval dt (s > 0).
  Eigen::Matrix3d GyroMeasurementCov(double dt) const;   // (rad/s)^2
  Eigen::Matrix3d AccelMeasurementCov(double dt) const;  // (m/s^2)^2
  // Covariance of the bias increment over dt (s >= 0).
  Eigen::Matrix3d GyroBiasWalkCov(double dt) const;   // (rad/s)^2
  Eigen::Matrix3d AccelBiasWalkCov(double dt) const;  // (m/s^2)^2
  // blockdiag of the four above, ordered [n_g, n_a, n_bg, n_ba].
  Matrix12d DiscreteCov(double dt) const;
  // Continuous spectral densities blockdiag(sigma^2 I), same order.
  Matrix12d ContinuousCov() const;
};

}  // namespace rvlio

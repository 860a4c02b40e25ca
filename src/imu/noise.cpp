#include "rvlio/imu/noise.h"

#include "rvlio/common/check.h"

namespace rvlio {
namespace {

Eigen::Matrix3d Isotropic(double variance) { return variance * Eigen::Matrix3d::Identity(); }

}  // namespace

ImuNoise ImuNoise::FromOptions(const ImuOptions& options) {
  ImuNoise n;
  n.gyro_noise_density = options.gyro_noise_density;
  n.accel_noise_density = options.accel_noise_density;
  n.gyro_bias_random_walk = options.gyro_bias_random_walk;
  n.accel_bias_random_walk = options.accel_bias_random_walk;
  return n;
}

// White noise sampled over dt: variance sigma^2 / dt.
Eigen::Matrix3d ImuNoise::GyroMeasurementCov(double dt) const {
  RVLIO_CHECK(dt > 0.0);
  return Isotropic(gyro_noise_density * gyro_noise_density / dt);
}

Eigen::Matrix3d ImuNoise::AccelMeasurementCov(double dt) const {
  RVLIO_CHECK(dt > 0.0);
  return Isotropic(accel_noise_density * accel_noise_density / dt);
}

// Random walk over dt: variance sigma_b^2 * dt.
Eigen::Matrix3d ImuNoise::GyroBiasWalkCov(double dt) const {
  RVLIO_CHECK(dt >= 0.0);
  return Isotropic(gyro_bias_random_walk * gyro_bias_random_walk * dt);
}

Eigen::Matrix3d ImuNoise::AccelBiasWalkCov(double dt) const {
  RVLIO_CHECK(dt >= 0.0);
  return Isotropic(accel_bias_random_walk * accel_bias_random_walk * dt);
}

Matrix12d ImuNoise::DiscreteCov(double dt) const {
  Matrix12d Q = Matrix12d::Zero();
  Q.block<3, 3>(kGyro, kGyro) = GyroMeasurementCov(dt);
  Q.block<3, 3>(kAccel, kAccel) = AccelMeasurementCov(dt);
  Q.block<3, 3>(kGyroBias, kGyroBias) = GyroBiasWalkCov(dt);
  Q.block<3, 3>(kAccelBias, kAccelBias) = AccelBiasWalkCov(dt);
  return Q;
}

Matrix12d ImuNoise::ContinuousCov() const {
  Matrix12d Q = Matrix12d::Zero();
  Q.block<3, 3>(kGyro, kGyro) = Isotropic(gyro_noise_density * gyro_noise_density);
  Q.block<3, 3>(kAccel, kAccel) = Isotropic(accel_noise_density * accel_noise_density);
  Q.block<3, 3>(kGyroBias, kGyroBias) = Isotropic(gyro_bias_random_walk * gyro_bias_random_walk);
  Q.block<3, 3>(kAccelBias, kAccelBias) =
      Isotropic(accel_bias_random_walk * accel_bias_random_walk);
  return Q;
}

}  // namespace rvlio

#pragma once
// Synthetic scenes shared by the benchmarks.
#include <random>
#include <vector>

#include <Eigen/Core>

#include "rvlio/imu/noise.h"

namespace rvlio::bench {

// IMU noise densities: gyro [rad/s/sqrt(Hz)], accel [m/s^2/sqrt(Hz)] and
// their bias random walks [rad/s^2/sqrt(Hz)], [m/s^3/sqrt(Hz)].
inline ImuNoise MakeImuNoise(double gyro, double accel, double gyro_walk, double accel_walk) {
  ImuNoise n;
  n.gyro_noise_density = gyro;
  n.accel_noise_density = accel;
  n.gyro_bias_random_walk = gyro_walk;
  n.accel_bias_random_walk = accel_walk;
  return n;
}

// Walls, floor and ceiling of a 10 x 8 m rectangular tunnel section,
// x in [-half_length, half_length] m, sampled every `step` m with 2 cm
// roughness (normal noise across each surface).
inline std::vector<Eigen::Vector3d> TunnelPoints(std::mt19937_64* rng, double step,
                                                 double half_length) {
  std::normal_distribution<double> n(0.0, 0.02);
  std::vector<Eigen::Vector3d> pts;
  for (double x = -half_length; x <= half_length; x += step) {
    for (double s = -5.0; s <= 5.0; s += step) {
      pts.emplace_back(x, s, 0.0 + n(*rng));
      pts.emplace_back(x, s, 8.0 + n(*rng));
    }
    for (double z = 0.0; z <= 8.0; z += step) {
      pts.emplace_back(x, -5.0 + n(*rng), z);
      pts.emplace_back(x, 5.0 + n(*rng), z);
    }
  }
  return pts;
}

}  // namespace rvlio::bench

// IMU noise: continuous densities -> discrete covariances, and a Monte Carlo
// check that the convention makes integrated noise independent of the rate.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/imu/noise.h"

namespace rvlio {
namespace {

ImuNoise TestNoise() {
  ImuOptions o;
  o.gyro_noise_density = 2e-3;
  o.accel_noise_density = 3e-2;
  o.gyro_bias_random_walk = 4e-4;
  o.accel_bias_random_walk = 5e-3;
  return ImuNoise::FromOptions(o);
}

TEST(ImuNoise, FromOptionsCopiesTheDensities) {
  const ImuOptions defaults;
  const ImuNoise n = ImuNoise::FromOptions(defaults);
  EXPECT_EQ(n.gyro_noise_density, defaults.gyro_noise_density);
  EXPECT_EQ(n.accel_noise_density, defaults.accel_noise_density);
  EXPECT_EQ(n.gyro_bias_random_walk, defaults.gyro_bias_random_walk);
  EXPECT_EQ(n.accel_bias_random_walk, defaults.accel_bias_random_walk);
}

TEST(ImuNoise, DiscreteCovarianceFollowsTheConvention) {
  const ImuNoise n = TestNoise();
  const double dt = 0.005;
  const Matrix12d Q = n.DiscreteCov(dt);
  const double expected[4] = {2e-3 * 2e-3 / dt, 3e-2 * 3e-2 / dt, 4e-4 * 4e-4 * dt,
                              5e-3 * 5e-3 * dt};
  const int offsets[4] = {ImuNoise::kGyro, ImuNoise::kAccel, ImuNoise::kGyroBias,
                          ImuNoise::kAccelBias};
  for (int b = 0; b < 4; ++b)
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(Q(offsets[b] + i, offsets[b] + i), expected[b], 1e-18);
  // Diagonal, and the sum of the block traces matches.
  EXPECT_NEAR(Q.trace(), 3.0 * (expected[0] + expected[1] + expected[2] + expected[3]), 1e-15);
  EXPECT_EQ((Q - Matrix12d(Q.diagonal().asDiagonal())).norm(), 0.0);
  const Matrix12d Qc = n.ContinuousCov();
  EXPECT_NEAR(Qc(ImuNoise::kGyro, ImuNoise::kGyro), 4e-6, 1e-20);
  EXPECT_NEAR(Qc(ImuNoise::kAccelBias + 2, ImuNoise::kAccelBias + 2), 2.5e-5, 1e-20);
}

// Integrating per-sample gyro noise over T seconds gives an angle random walk
// of variance sigma^2 T whatever the sample rate; summing bias increments
// gives a bias variance sigma_b^2 T.
TEST(ImuNoise, IntegratedNoiseIsIndependentOfRate) {
  const ImuNoise n = TestNoise();
  const double T = 1.0;
  std::mt19937 rng(51);
  std::normal_distribution<double> unit(0.0, 1.0);
  for (double rate_hz : {100.0, 800.0}) {
    const double dt = 1.0 / rate_hz;
    const int steps = static_cast<int>(std::lround(T * rate_hz));
    const double std_meas = std::sqrt(n.GyroMeasurementCov(dt)(0, 0));
    const double std_walk = std::sqrt(n.GyroBiasWalkCov(dt)(0, 0));
    const int trials = 2000;
    double sum_angle2 = 0.0, sum_bias2 = 0.0;
    for (int k = 0; k < trials; ++k) {
      double angle = 0.0, bias = 0.0;
      for (int i = 0; i < steps; ++i) {
        angle += std_meas * unit(rng) * dt;
        bias += std_walk * unit(rng);
      }
      sum_angle2 += angle * angle;
      sum_bias2 += bias * bias;
    }
    // 2000 samples of a chi-square: relative standard error sqrt(2/2000) = 3.2%.
    const double var_angle = sum_angle2 / trials, var_bias = sum_bias2 / trials;
    EXPECT_NEAR(var_angle / (n.gyro_noise_density * n.gyro_noise_density * T), 1.0, 0.12)
        << rate_hz;
    EXPECT_NEAR(var_bias / (n.gyro_bias_random_walk * n.gyro_bias_random_walk * T), 1.0, 0.12)
        << rate_hz;
  }
}

}  // namespace
}  // namespace rvlio

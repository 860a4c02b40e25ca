// IMU preintegration factor: zero residual at the true states of a
// noise-free simulation, analytic Jacobians against numeric differences
// through the manifold, whitening consistent with the noise.
#include <random>

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include "rvlio/factors/imu_factor.h"
#include "rvlio/factors/manifolds.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

ImuNoise Noise() {
  ImuNoise n;
  n.gyro_noise_density = 1e-3;
  n.accel_noise_density = 1e-2;
  n.gyro_bias_random_walk = 1e-4;
  n.accel_bias_random_walk = 1e-3;
  return n;
}

ImuFactor MakeFactor(TimeNs t0, TimeNs t1, TimeNs period, const Vector3d& bg, const Vector3d& ba,
                     const Vector3d& bg_lin, const Vector3d& ba_lin) {
  const auto samples = test::SimulateImu(t0, t1, period, bg, ba);
  return ImuFactor(ImuPreintegration::FromSamples(samples, t0, t1, Noise(), bg_lin, ba_lin),
                   test::Gravity());
}

TEST(ImuFactor, ResidualVanishesAtTheTrueStates) {
  const Vector3d bg(0.003, -0.002, 0.001), ba(0.04, -0.03, 0.05);
  for (TimeNs t0 : {TimeNs(12345), TimeNs(700000000), TimeNs(2 * kNsPerSecond + 99)}) {
    const TimeNs t1 = t0 + 100000000 + 777;  // one 10 Hz scan, unaligned with the 1 kHz IMU
    const ImuFactor f = MakeFactor(t0, t1, 1000000, bg, ba, bg, ba);
    const Vector15d r = f.Residual(test::TruePose(t0), test::TrueSpeedBias(t0, bg, ba),
                                   test::TruePose(t1), test::TrueSpeedBias(t1, bg, ba));
    // Second-order discretization error at 1 kHz: measured <= 2e-8 rad.
    EXPECT_LT(r.segment<3>(ImuFactor::kR).norm(), 5e-8) << r.transpose();
    EXPECT_LT(r.segment<3>(ImuFactor::kV).norm(), 1e-7) << r.transpose();
    EXPECT_LT(r.segment<3>(ImuFactor::kP).norm(), 1e-8) << r.transpose();
    EXPECT_EQ(r.tail<6>().norm(), 0.0);
    // Linearized at zero bias, the first-order correction recovers the truth
    // up to a second-order remainder.
    const ImuFactor g = MakeFactor(t0, t1, 1000000, bg, ba, Vector3d::Zero(), Vector3d::Zero());
    const Vector15d r0 = g.Residual(test::TruePose(t0), test::TrueSpeedBias(t0, bg, ba),
                                    test::TruePose(t1), test::TrueSpeedBias(t1, bg, ba));
    EXPECT_LT(r0.head<9>().norm(), 1e-6) << r0.transpose();
    // Whitened through Evaluate: the same residual times S.
    const auto v = std::vector<std::vector<double>>{
        test::ToVector(test::TruePose(t0)), test::ToVector(test::TrueSpeedBias(t0, bg, ba)),
        test::ToVector(test::TruePose(t1)), test::ToVector(test::TrueSpeedBias(t1, bg, ba))};
    EXPECT_LT((test::EvaluateCost(f, v) - f.sqrt_information() * r).norm(), 1e-12);
  }
}

TEST(ImuFactor, SqrtInformationWhitensTheCovariance) {
  const ImuFactor f = MakeFactor(0, 100000000, 5000000, Vector3d::Zero(), Vector3d::Zero(),
                                 Vector3d::Zero(), Vector3d::Zero());
  const Matrix15d I = f.sqrt_information() * f.covariance() * f.sqrt_information().transpose();
  EXPECT_LT((I - Matrix15d::Identity()).cwiseAbs().maxCoeff(), 1e-8);
  // Bias rows: random walk over dt.
  EXPECT_NEAR(f.covariance()(ImuFactor::kBa, ImuFactor::kBa), 1e-6 * 0.1, 1e-15);
}

TEST(ImuFactor, AnalyticJacobiansMatchNumericThroughTheManifold) {
  // Random (inconsistent) states, so that every term of the Jacobian is
  // exercised, including the bias correction away from the linearization point.
  std::mt19937 rng(21);
  const PoseManifold pose_manifold;
  const std::vector<const ceres::Manifold*> manifolds = {&pose_manifold, nullptr, &pose_manifold,
                                                         nullptr};
  for (int trial = 0; trial < 30; ++trial) {
    const TimeNs t0 = 50000000 * trial + 31, t1 = t0 + 100000000 + 4321;
    const ImuFactor f = MakeFactor(t0, t1, 5000000, test::RandomVector(rng, 0.01),
                                   test::RandomVector(rng, 0.1), test::RandomVector(rng, 0.01),
                                   test::RandomVector(rng, 0.1));
    const std::vector<std::vector<double>> v = {
        test::ToVector(test::RandomPose(rng)), test::ToVector(test::RandomSpeedBias(rng)),
        test::ToVector(test::RandomPose(rng)), test::ToVector(test::RandomSpeedBias(rng))};
    EXPECT_LT(test::TangentJacobianError(f, v, manifolds), 1e-6) << trial;
  }
}

TEST(ImuFactor, PassesCeresGradientChecker) {
  // Near the true states (the operating regime), with Ceres' own checker.
  std::mt19937 rng(22);
  const PoseManifold pose_manifold;
  const std::vector<const ceres::Manifold*> manifolds = {&pose_manifold, nullptr, &pose_manifold,
                                                         nullptr};
  const Vector3d bg(0.002, 0.001, -0.003), ba(0.02, -0.01, 0.03);
  const TimeNs t0 = 300000000, t1 = 400000000;
  const ImuFactor f = MakeFactor(t0, t1, 5000000, bg, ba, Vector3d::Zero(), Vector3d::Zero());
  ceres::NumericDiffOptions numeric_options;
  ceres::GradientChecker checker(&f, &manifolds, numeric_options);
  for (int trial = 0; trial < 10; ++trial) {
    Eigen::Matrix<double, 6, 1> d;
    d << test::RandomVector(rng, 0.01), test::RandomVector(rng, 0.02);
    const auto p0 = test::ToVector(Plus(test::TruePose(t0), d));
    const auto s0 = test::ToVector(test::TrueSpeedBias(t0, bg, ba));
    const auto p1 = test::ToVector(test::TruePose(t1));
    const auto s1 = test::ToVector(test::TrueSpeedBias(t1, bg + test::RandomVector(rng, 1e-3), ba));
    const double* params[] = {p0.data(), s0.data(), p1.data(), s1.data()};
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(params, 1e-6, &results)) << results.error_log;
  }
}

TEST(ImuFactor, WhitenedResidualIsChiSquaredUnderNoise) {
  // Noisy IMU samples (per-sample white noise, ImuNoise's convention); at the
  // true states, |S r|^2 over the 9 motion rows averages ~9.
  const ImuNoise noise = Noise();
  const TimeNs period = 5000000, t0 = 1000000, t1 = 101000000;
  const auto clean = test::SimulateImu(t0, t1, period);
  std::mt19937 rng(23);
  const double sg = noise.gyro_noise_density / std::sqrt(NsToSeconds(period));
  const double sa = noise.accel_noise_density / std::sqrt(NsToSeconds(period));
  const int kTrials = 1000;
  double sum = 0.0;
  const Vector3d z = Vector3d::Zero();
  for (int trial = 0; trial < kTrials; ++trial) {
    auto noisy = clean;
    for (ImuSample& s : noisy) {
      s.gyro_imu += test::RandomVector(rng, sg);
      s.acc_imu += test::RandomVector(rng, sa);
    }
    const ImuFactor f(ImuPreintegration::FromSamples(noisy, t0, t1, noise, z, z), test::Gravity());
    const Vector15d r = f.sqrt_information() *
                        f.Residual(test::TruePose(t0), test::TrueSpeedBias(t0, z, z),
                                   test::TruePose(t1), test::TrueSpeedBias(t1, z, z));
    sum += r.squaredNorm();
  }
  // Std of the mean of a chi^2(9): sqrt(18 / 1000) = 0.13.
  EXPECT_NEAR(sum / kTrials, 9.0, 0.9);
}

}  // namespace
}  // namespace rvlio

// The window's prior factors (factors/prior_factor.h): residual values and
// analytic Jacobians against central differences through the manifolds.
#include <random>

#include <gtest/gtest.h>

#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/prior_factor.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

TEST(StatePriorFactor, ResidualIsTheWhitenedDifference) {
  std::mt19937 rng(1);
  const PoseBlock pose0 = test::RandomPose(rng);
  const SpeedBiasBlock sb0 = test::RandomSpeedBias(rng);
  StatePriorStd std;
  std.rot = 0.01;
  std.pos = 0.02;
  std.vel = 0.5;
  std.bg = 1e-3;
  std.ba = 0.04;
  const StatePriorFactor prior(pose0, sb0, std);
  // Zero at the prior's own values.
  EXPECT_LT(test::EvaluateCost(prior, {test::ToVector(pose0), test::ToVector(sb0)}).norm(), 1e-12);
  // A known offset in every component.
  Eigen::Matrix<double, 6, 1> d;
  d << 0.003, -0.002, 0.001, 0.1, 0.2, -0.3;
  SpeedBiasBlock sb = sb0;
  sb.v_world_imu += Vector3d(0.5, 0.0, 0.0);
  sb.bg += Vector3d(0.0, 1e-3, 0.0);
  sb.ba += Vector3d(0.0, 0.0, 0.08);
  const Eigen::VectorXd r =
      test::EvaluateCost(prior, {test::ToVector(Plus(pose0, d)), test::ToVector(sb)});
  Eigen::Matrix<double, 15, 1> expected;
  expected << d.head<3>() / 0.01, d.tail<3>() / 0.02, 1.0, 0, 0, 0, 1.0, 0, 0, 0, 2.0;
  EXPECT_LT((r - expected).norm(), 1e-9) << r.transpose();
}

TEST(StatePriorFactor, JacobianMatchesNumericDifferences) {
  std::mt19937 rng(2);
  PoseManifold manifold;
  for (int trial = 0; trial < 50; ++trial) {
    const PoseBlock pose0 = test::RandomPose(rng);
    const StatePriorFactor prior(pose0, test::RandomSpeedBias(rng), StatePriorStd());
    Eigen::Matrix<double, 6, 1> d;
    d << test::RandomVector(rng, 0.5), test::RandomVector(rng, 1.0);  // far from pose0
    const std::vector<std::vector<double>> values = {test::ToVector(Plus(pose0, d)),
                                                     test::ToVector(test::RandomSpeedBias(rng))};
    // Residuals ~1e3 (stds of 1e-3): relative error 1e-7 is rounding.
    EXPECT_LT(test::TangentJacobianError(prior, values, {&manifold, nullptr}), 1e-7) << trial;
  }
}

TEST(SpeedBiasContinuityFactor, ResidualAndJacobian) {
  std::mt19937 rng(3);
  const SpeedBiasContinuityFactor factor(2.0, 1e-3, 0.1);
  for (int trial = 0; trial < 20; ++trial) {
    const SpeedBiasBlock a = test::RandomSpeedBias(rng), b = test::RandomSpeedBias(rng);
    const Eigen::VectorXd r = test::EvaluateCost(factor, {test::ToVector(a), test::ToVector(b)});
    Eigen::Matrix<double, 9, 1> expected;
    expected << (b.v_world_imu - a.v_world_imu) / 2.0, (b.bg - a.bg) / 1e-3, (b.ba - a.ba) / 0.1;
    EXPECT_LT((r - expected).norm(), 1e-9);
    EXPECT_LT(test::TangentJacobianError(factor, {test::ToVector(a), test::ToVector(b)},
                                         {nullptr, nullptr}),
              1e-8);
  }
}

}  // namespace
}  // namespace rvlio

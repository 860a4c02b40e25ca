// The plane factor with the time offset as a parameter
// (lidar.estimate_time_offset in the smoother): residuals equal the shared
// time-offset model, Jacobians (pose, speed-bias, offset) match numeric
// differences through the manifold (Ceres' GradientChecker).
#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

#include <ceres/gradient_checker.h>
#include <ceres/normal_prior.h>
#include <gtest/gtest.h>

#include "rvlio/constraints/time_offset_residual.h"
#include "rvlio/smoother/manifolds.h"
#include "rvlio/smoother/marginalization.h"
#include "rvlio/smoother/plane_time_offset_factor.h"
#include "smoother_test_util.h"

namespace rvlio {
namespace {

using test::RandomConstraints;

ScanTimeMotion SomeMotion() {
  ScanTimeMotion m;
  m.gyro_imu = Eigen::Vector3d(0.5, -0.8, 0.6);
  m.acc_world = Eigen::Vector3d(0.4, 1.2, -0.7);
  return m;
}

std::vector<double> SpeedBias() { return {1.1, -0.6, 0.4, 0.01, -0.02, 0.03, 0.1, 0.2, -0.1}; }

TEST(PlaneTimeOffsetFactor, ResidualsAreTheSharedModelScaledByWeight) {
  std::mt19937 rng(51);
  const ConstraintList list = RandomConstraints(rng, 30);
  const double sigma = 0.05, td_lin = 0.03, td = 0.07;
  const PoseBlock ext = test::RandomPose(rng), pose = test::RandomPose(rng);
  const PlaneTimeOffsetFactor f(list, sigma, ext.ToPose3(), SomeMotion(), td_lin);
  ASSERT_EQ(f.num_residuals(), 30);
  const std::vector<double> sb = SpeedBias();
  const Eigen::VectorXd r = test::EvaluateCost(f, {test::ToVector(pose), sb, {td}});
  FilterState x;
  x.R_world_imu = pose.ToPose3().R;
  x.p_world_imu = pose.ToPose3().t;
  x.v_world_imu = Eigen::Vector3d(sb[0], sb[1], sb[2]);
  x.R_imu_lidar = ext.ToPose3().R;
  x.t_imu_lidar = ext.ToPose3().t;
  for (size_t i = 0; i < list.size(); ++i) {
    const double expected = std::sqrt(list[i].weight) / sigma *
                            PointToPlaneResidualWithTimeOffset(list[i], x, SomeMotion(), td - td_lin);
    EXPECT_NEAR(r(i), expected, 1e-10 * std::max(1.0, std::abs(expected)));
  }
}

TEST(PlaneTimeOffsetFactor, JacobiansMatchNumericDifferences) {
  std::mt19937 rng(52);
  const PoseManifold m;
  const std::vector<const ceres::Manifold*> manifolds = {&m, nullptr, nullptr};
  for (double td : {0.03, -0.09, 0.15}) {
    const PlaneTimeOffsetFactor f(RandomConstraints(rng, 25), 0.1, test::RandomPose(rng).ToPose3(),
                                  SomeMotion(), 0.03);
    ceres::GradientChecker checker(&f, &manifolds, ceres::NumericDiffOptions());
    const auto x = test::ToVector(test::RandomPose(rng));
    const std::vector<double> sb = SpeedBias();
    const double* params[] = {x.data(), sb.data(), &td};
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(params, 1e-7, &results)) << "td " << td << ": " << results.error_log;
  }
}

TEST(TimeOffsetRandomWalkFactor, ResidualAndJacobiansMatchNumericDifferences) {
  const TimeOffsetRandomWalkFactor f(1e-3, 0.25);  // sigma = 1e-3 * 0.5 s
  EXPECT_NEAR(test::EvaluateCost(f, {{0.031}, {0.032}})(0), (0.032 - 0.031) / 5e-4, 1e-9);
  const std::vector<const ceres::Manifold*> euclidean = {nullptr, nullptr};
  ceres::GradientChecker checker(&f, &euclidean, ceres::NumericDiffOptions());
  for (const auto& [td_prev, td] : {std::pair{0.03, 0.031}, std::pair{-0.1, 0.05}}) {
    const double* params[] = {&td_prev, &td};
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(params, 1e-9, &results)) << results.error_log;
  }
}

// Marginalizing the previous offset through the random walk leaves the
// window's offset with the prior's variance grown by q^2 dt.
TEST(TimeOffsetRandomWalkFactor, MarginalizedPriorGrowsByTheWalk) {
  const double prior_std = 2e-3, q = 1e-3, dt = 0.5;
  ceres::Matrix A(1, 1);
  A(0, 0) = 1.0 / prior_std;
  ceres::Vector b(1);
  b(0) = 0.03;
  const ceres::NormalPrior prior(A, b);
  const TimeOffsetRandomWalkFactor walk(q, dt);
  double td_prev = 0.03, td = 0.03;
  MarginalizationInfo info;
  info.AddResidualBlock(&prior, nullptr, {&td_prev}, {0});
  info.AddResidualBlock(&walk, nullptr, {&td_prev, &td}, {0});
  ASSERT_TRUE(info.Marginalize().ok());
  const MarginalizationPrior& p = *info.prior();
  ASSERT_EQ(p.tangent_dim, 1);
  const double information = (p.S.transpose() * p.S)(0, 0);
  EXPECT_NEAR(1.0 / information, prior_std * prior_std + q * q * dt, 1e-12);
}

}  // namespace
}  // namespace rvlio

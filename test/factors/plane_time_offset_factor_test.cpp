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
#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/marginalization.h"
#include "rvlio/factors/plane_time_offset_factor.h"
#include "support/smoother_test_util.h"

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

// The summary equals the per-point residuals of the shared model
// sqrt(weight_i) / sigma * PointToPlaneResidualWithTimeOffset: the same cost,
// the same J^T r and J^T J over [dtheta, dp, dv, d(td)].
TEST(PlaneTimeOffsetFactor, SummaryEqualsThePerPointResiduals) {
  std::mt19937 rng(51);
  const ConstraintList list = RandomConstraints(rng, 30);
  const double sigma = 0.05, td_lin = 0.03, td = 0.07;
  const PoseBlock ext = test::RandomPose(rng), pose = test::RandomPose(rng);
  const PlaneTimeOffsetFactor f(list, sigma, ext.ToPose3(), SomeMotion(), td_lin,
                                pose.ToPose3().t + Eigen::Vector3d(0.5, -0.2, 0.1));
  ASSERT_EQ(f.num_residuals(), 13);
  const std::vector<double> sb = SpeedBias();
  const std::vector<double> pose_v = test::ToVector(pose);
  const double* params[] = {pose_v.data(), sb.data(), &td};
  Eigen::Matrix<double, 13, 1> r;
  Eigen::Matrix<double, 13, 7, Eigen::RowMajor> J_pose_ambient;
  Eigen::Matrix<double, 13, 9, Eigen::RowMajor> J_sb;
  Eigen::Matrix<double, 13, 1> J_td;
  double* jacobians[] = {J_pose_ambient.data(), J_sb.data(), J_td.data()};
  ASSERT_TRUE(f.Evaluate(params, r.data(), jacobians));
  // The tangent pose Jacobian: ambient times PlusJacobian.
  const PoseManifold m;
  Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus;
  ASSERT_TRUE(m.PlusJacobian(pose_v.data(), plus.data()));
  Eigen::Matrix<double, 13, 10> J;  // [dtheta, dp, dv, d(td)]
  J << J_pose_ambient * plus, J_sb.middleCols<3>(SpeedBiasBlock::kVel), J_td;

  FilterState x;
  x.R_world_imu = pose.ToPose3().R;
  x.p_world_imu = pose.ToPose3().t;
  x.v_world_imu = Eigen::Vector3d(sb[0], sb[1], sb[2]);
  x.R_imu_lidar = ext.ToPose3().R;
  x.t_imu_lidar = ext.ToPose3().t;
  double cost = 0.0;
  Eigen::Matrix<double, 10, 1> Jtr = Eigen::Matrix<double, 10, 1>::Zero();
  Eigen::Matrix<double, 10, 10> JtJ = Eigen::Matrix<double, 10, 10>::Zero();
  for (const Constraint& c : list) {
    TimeOffsetJacobian h;
    const double s = std::sqrt(c.weight) / sigma;
    const double ri = s * PointToPlaneResidualWithTimeOffset(c, x, SomeMotion(), td - td_lin, &h);
    Eigen::Matrix<double, 1, 10> hi;
    hi << s * h.head<6>(), s * h.segment<4>(12);
    cost += ri * ri;
    Jtr += hi.transpose() * ri;
    JtJ += hi.transpose() * hi;
  }
  EXPECT_NEAR(r.squaredNorm(), cost, 1e-8 * cost);
  EXPECT_LT((J.transpose() * r - Jtr).norm(), 1e-7 * Jtr.norm());
  EXPECT_LT((J.transpose() * J - JtJ).norm(), 1e-7 * JtJ.norm());
}

TEST(PlaneTimeOffsetFactor, JacobiansMatchNumericDifferences) {
  std::mt19937 rng(52);
  const PoseManifold m;
  const std::vector<const ceres::Manifold*> manifolds = {&m, nullptr, nullptr};
  for (double td : {0.03, -0.09, 0.15}) {
    const PlaneTimeOffsetFactor f(RandomConstraints(rng, 25), 0.1, test::RandomPose(rng).ToPose3(),
                                  SomeMotion(), 0.03, Eigen::Vector3d(1.0, 2.0, -0.5));
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

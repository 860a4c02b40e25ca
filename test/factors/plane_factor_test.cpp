// One point-to-plane factor per scan: residuals equal the shared model
// (constraints/point_to_plane.h) scaled by sqrt(weight)/sigma, Jacobians match
// numeric differences through the manifold.
#include <random>

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/plane_factor.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using test::RandomConstraints;

Pose3 RandomExtrinsics(std::mt19937& rng) {
  return test::RandomPose(rng).ToPose3();
}

TEST(PlaneFactor, ResidualsAreTheSharedModelScaledByWeight) {
  std::mt19937 rng(31);
  for (int trial = 0; trial < 20; ++trial) {
    const ConstraintList list = RandomConstraints(rng, 1 + trial * 7);
    const Pose3 T_il = RandomExtrinsics(rng);
    const double sigma = 0.05;
    const PlaneFactor f(list, T_il, sigma);
    ASSERT_EQ(f.num_residuals(), static_cast<int>(list.size()));
    ASSERT_EQ(f.num_constraints(), static_cast<int>(list.size()));
    ASSERT_EQ(f.parameter_block_sizes().size(), 1u);
    const PoseBlock pose = test::RandomPose(rng);
    const Eigen::VectorXd r = test::EvaluateCost(f, {test::ToVector(pose)});
    for (size_t i = 0; i < list.size(); ++i) {
      const double expected =
          std::sqrt(list[i].weight) / sigma * PointToPlaneResidual(list[i], pose.ToPose3(), T_il);
      EXPECT_NEAR(r(i), expected, 1e-10 * std::max(1.0, std::abs(expected)));
    }
  }
}

TEST(PlaneFactor, TangentJacobianIsTheSharedModelsJacobian) {
  std::mt19937 rng(32);
  const PoseManifold m;
  for (int trial = 0; trial < 20; ++trial) {
    const ConstraintList list = RandomConstraints(rng, 50);
    const Pose3 T_il = RandomExtrinsics(rng);
    const PlaneFactor f(list, T_il, 0.02);
    const auto x = test::ToVector(test::RandomPose(rng));
    std::vector<test::RowMajorMatrix> J;
    test::EvaluateCost(f, {x}, &J);
    test::RowMajorMatrix plus(7, 6);
    m.PlusJacobian(x.data(), plus.data());
    const Eigen::MatrixXd J_t = J[0] * plus;
    for (size_t i = 0; i < list.size(); ++i) {
      Eigen::Matrix<double, 1, 6> row;
      PointToPlaneResidual(list[i], PoseBlock::FromArray(x.data()).ToPose3(), T_il, &row);
      row *= std::sqrt(list[i].weight) / 0.02;
      EXPECT_LT((J_t.row(i) - row).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, row.norm()));
    }
  }
}

TEST(PlaneFactor, AnalyticJacobianMatchesNumericThroughTheManifold) {
  std::mt19937 rng(33);
  const PoseManifold m;
  for (int trial = 0; trial < 30; ++trial) {
    const PlaneFactor f(RandomConstraints(rng, 40), RandomExtrinsics(rng), 0.1);
    EXPECT_LT(test::TangentJacobianError(f, {test::ToVector(test::RandomPose(rng))}, {&m}), 1e-7);
  }
  // And with Ceres' checker.
  const std::vector<const ceres::Manifold*> manifolds = {&m};
  const PlaneFactor f(RandomConstraints(rng, 40), RandomExtrinsics(rng), 0.1);
  ceres::GradientChecker checker(&f, &manifolds, ceres::NumericDiffOptions());
  const auto x = test::ToVector(test::RandomPose(rng));
  const double* params[] = {x.data()};
  ceres::GradientChecker::ProbeResults results;
  EXPECT_TRUE(checker.Probe(params, 1e-7, &results)) << results.error_log;
}

TEST(PlaneFactor, ZeroWeightSilencesAConstraint) {
  std::mt19937 rng(34);
  ConstraintList list = RandomConstraints(rng, 3);
  list[1].weight = 0.0;
  const PlaneFactor f(list, Pose3(), 0.1);
  std::vector<test::RowMajorMatrix> J;
  const Eigen::VectorXd r = test::EvaluateCost(f, {test::ToVector(test::RandomPose(rng))}, &J);
  EXPECT_EQ(r(1), 0.0);
  EXPECT_EQ(J[0].row(1).norm(), 0.0);
  EXPECT_GT(std::abs(r(0)), 0.0);
}

}  // namespace
}  // namespace rvlio

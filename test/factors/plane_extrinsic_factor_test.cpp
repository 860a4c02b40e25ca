// The plane factor with the extrinsic as a parameter block
// (smoother.estimate_extrinsics): residuals equal the shared model, Jacobians
// (pose and extrinsic) match numeric differences through the manifold; the
// subset manifold that holds unexcited extrinsic axes; the extrinsic prior.
#include <random>

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/plane_extrinsic_factor.h"
#include "rvlio/factors/prior_factor.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using test::RandomConstraints;

TEST(PlaneExtrinsicFactor, ResidualsAreTheSharedModelScaledByWeight) {
  std::mt19937 rng(41);
  const ConstraintList list = RandomConstraints(rng, 30);
  const double sigma = 0.05;
  const PlaneExtrinsicFactor f(list, sigma);
  ASSERT_EQ(f.num_residuals(), 30);
  const PoseBlock pose = test::RandomPose(rng), ext = test::RandomPose(rng);
  const Eigen::VectorXd r = test::EvaluateCost(f, {test::ToVector(pose), test::ToVector(ext)});
  for (size_t i = 0; i < list.size(); ++i) {
    const double expected = std::sqrt(list[i].weight) / sigma *
                            PointToPlaneResidual(list[i], pose.ToPose3(), ext.ToPose3());
    EXPECT_NEAR(r(i), expected, 1e-10 * std::max(1.0, std::abs(expected)));
  }
}

TEST(PlaneExtrinsicFactor, PoseAndExtrinsicJacobiansMatchNumericDifferences) {
  std::mt19937 rng(42);
  const PoseManifold m;
  for (int trial = 0; trial < 20; ++trial) {
    const PlaneExtrinsicFactor f(RandomConstraints(rng, 25), 0.1);
    EXPECT_LT(test::TangentJacobianError(
                  f, {test::ToVector(test::RandomPose(rng)), test::ToVector(test::RandomPose(rng))},
                  {&m, &m}),
              1e-7);
  }
  const std::vector<const ceres::Manifold*> manifolds = {&m, &m};
  const PlaneExtrinsicFactor f(RandomConstraints(rng, 25), 0.1);
  ceres::GradientChecker checker(&f, &manifolds, ceres::NumericDiffOptions());
  const auto x = test::ToVector(test::RandomPose(rng)), e = test::ToVector(test::RandomPose(rng));
  const double* params[] = {x.data(), e.data()};
  ceres::GradientChecker::ProbeResults results;
  EXPECT_TRUE(checker.Probe(params, 1e-7, &results)) << results.error_log;
}

TEST(PoseSubsetManifold, MovesOnlyTheFreeAxesAndIsConsistent) {
  std::mt19937 rng(43);
  const std::array<bool, 6> free = {true, false, true, true, false, false};
  const PoseSubsetManifold sub(free);
  ASSERT_EQ(sub.TangentSize(), 3);
  const auto x = test::ToVector(test::RandomPose(rng));
  const double delta[3] = {0.01, -0.02, 0.03};
  double y[7];
  ASSERT_TRUE(sub.Plus(x.data(), delta, y));
  double full[6];
  PoseBlock::Minus(y, x.data(), full);
  EXPECT_NEAR(full[0], 0.01, 1e-12);
  EXPECT_NEAR(full[1], 0.0, 1e-12);
  EXPECT_NEAR(full[2], -0.02, 1e-12);
  EXPECT_NEAR(full[3], 0.03, 1e-12);
  EXPECT_EQ(y[5], x[5]);  // translation y held exactly
  EXPECT_EQ(y[6], x[6]);
  double back[3];
  ASSERT_TRUE(sub.Minus(y, x.data(), back));
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(back[i], delta[i], 1e-12);
  // MinusJacobian * PlusJacobian = I (3x3).
  Eigen::Matrix<double, 7, 3, Eigen::RowMajor> P;
  Eigen::Matrix<double, 3, 7, Eigen::RowMajor> M;
  ASSERT_TRUE(sub.PlusJacobian(x.data(), P.data()));
  ASSERT_TRUE(sub.MinusJacobian(x.data(), M.data()));
  EXPECT_TRUE((M * P).isIdentity(1e-12));
}

TEST(PosePriorFactor, JacobianMatchesNumericDifferences) {
  std::mt19937 rng(44);
  const PoseManifold m;
  const PosePriorFactor f(test::RandomPose(rng), 0.05, 0.1);
  EXPECT_LT(test::TangentJacobianError(f, {test::ToVector(test::RandomPose(rng))}, {&m}), 1e-7);
  const PoseBlock at = test::RandomPose(rng);
  const PosePriorFactor g(at, 0.05, 0.1);
  EXPECT_LT(test::EvaluateCost(g, {test::ToVector(at)}).norm(), 1e-12);
}

}  // namespace
}  // namespace rvlio

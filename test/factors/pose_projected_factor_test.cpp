// PoseProjectedFactor (the smoother's remap): along the held pose directions
// the wrapped factor is constant through pose0; across them it is the inner
// factor of the projected pose; its Jacobians match numeric differences
// through the manifold, for a one-block and a two-block inner factor, and
// with both pose blocks of a two-block factor projected (refine's pairs).
#include <random>

#include <Eigen/QR>
#include <gtest/gtest.h>

#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/plane_extrinsic_factor.h"
#include "rvlio/factors/plane_summary_factor.h"
#include "rvlio/factors/pose_projected_factor.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using HeldDirections = PoseProjectedFactor::Directions;

// k orthonormal random pose directions.
HeldDirections RandomHeld(std::mt19937& rng, int k) {
  Eigen::Matrix<double, 6, 6> A;
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 36; ++i) A.data()[i] = n(rng);
  const Eigen::HouseholderQR<Eigen::Matrix<double, 6, 6>> qr(A);
  const Eigen::Matrix<double, 6, 6> Q = qr.householderQ();
  return Q.leftCols(k);
}

PoseBlock Near(std::mt19937& rng, const PoseBlock& x, double scale) {
  PoseBlock::Tangent d;
  std::normal_distribution<double> n(0.0, scale);
  for (int i = 0; i < 6; ++i) d(i) = n(rng);
  return Plus(x, d);
}

TEST(PoseProjectedFactor, ConstantAlongTheHeldDirectionsAndTheInnerFactorAcross) {
  std::mt19937 rng(71);
  for (int trial = 0; trial < 20; ++trial) {
    const ConstraintList list = test::RandomConstraints(rng, 40);
    const PoseBlock pose0 = test::RandomPose(rng);
    const PlaneSummaryFactor inner(list, Pose3(), 0.02, pose0.p_world_imu);
    const int k = 1 + trial % 3;
    const HeldDirections V = RandomHeld(rng, k);
    const PoseProjectedFactor f(&inner, pose0, V);
    ASSERT_EQ(f.num_residuals(), inner.num_residuals());
    ASSERT_EQ(f.parameter_block_sizes(), inner.parameter_block_sizes());
    // Across V: x = pose0 [+] d with d orthogonal to V is seen as it is.
    PoseBlock::Tangent d = 0.05 * PoseBlock::Tangent::Random();
    d -= V * (V.transpose() * d);
    const PoseBlock x = Plus(pose0, d);
    const Eigen::VectorXd r_inner = test::EvaluateCost(inner, {test::ToVector(x)});
    const Eigen::VectorXd r = test::EvaluateCost(f, {test::ToVector(x)});
    EXPECT_LT((r - r_inner).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, r_inner.norm()));
    // Along V: moving x by any amount along V changes nothing.
    const PoseBlock::Tangent along = V * Eigen::VectorXd::Random(k);
    const PoseBlock x_moved = Plus(pose0, d + along);
    const Eigen::VectorXd r_moved = test::EvaluateCost(f, {test::ToVector(x_moved)});
    EXPECT_LT((r_moved - r).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, r.norm()));
  }
}

TEST(PoseProjectedFactor, InformationAlongTheHeldDirectionsIsZero) {
  std::mt19937 rng(72);
  const PoseManifold m;
  for (int trial = 0; trial < 10; ++trial) {
    const ConstraintList list = test::RandomConstraints(rng, 60);
    const PoseBlock pose0 = test::RandomPose(rng);
    const PlaneSummaryFactor inner(list, Pose3(), 0.02, pose0.p_world_imu);
    const HeldDirections V = RandomHeld(rng, 2);
    const PoseProjectedFactor f(&inner, pose0, V);
    const auto x = test::ToVector(Near(rng, pose0, 0.03));
    std::vector<test::RowMajorMatrix> J;
    test::EvaluateCost(f, {x}, &J);
    test::RowMajorMatrix plus(7, 6);
    m.PlusJacobian(x.data(), plus.data());
    const Eigen::MatrixXd J_t = J[0] * plus;
    // At pose0 the tangent Jacobian annihilates V exactly; nearby, to first order.
    const double scale = J_t.cwiseAbs().maxCoeff();
    EXPECT_GT(scale, 1.0);
    EXPECT_LT((J_t * V).cwiseAbs().maxCoeff(), 0.05 * scale);
    std::vector<test::RowMajorMatrix> J0;
    test::EvaluateCost(f, {test::ToVector(pose0)}, &J0);
    m.PlusJacobian(test::ToVector(pose0).data(), plus.data());
    EXPECT_LT(((J0[0] * plus) * V).cwiseAbs().maxCoeff(), 1e-12 * scale);
  }
}

TEST(PoseProjectedFactor, JacobiansMatchNumericDifferences) {
  std::mt19937 rng(73);
  const PoseManifold m;
  for (int trial = 0; trial < 20; ++trial) {
    const ConstraintList list = test::RandomConstraints(rng, 30);
    const PoseBlock pose0 = test::RandomPose(rng);
    const HeldDirections V = RandomHeld(rng, 1 + trial % 4);
    const auto x = test::ToVector(Near(rng, pose0, 0.2));
    const PlaneSummaryFactor summary(list, Pose3(), 0.02, pose0.p_world_imu);
    const PoseProjectedFactor one(&summary, pose0, V);
    EXPECT_LT(test::TangentJacobianError(one, {x}, {&m}), 1e-5) << "trial " << trial;
    const PlaneExtrinsicFactor with_extrinsic(list, 0.02);
    const PoseProjectedFactor two(&with_extrinsic, pose0, V);
    const auto ext = test::ToVector(Near(rng, PoseBlock(Pose3()), 0.05));
    EXPECT_LT(test::TangentJacobianError(two, {x, ext}, {&m, &m}), 1e-5) << "trial " << trial;
  }
}

// Refine's pair factors: both pose blocks projected, each through its own
// pose0 and directions. The factor is constant along each block's
// directions, its Jacobians match numeric differences, and a constant first
// block (no Jacobian asked for it, as Ceres does for a held pose) leaves the
// second block's Jacobian as it is.
TEST(PoseProjectedFactor, TwoProjectedBlocksAreEachConstantAlongTheirDirections) {
  std::mt19937 rng(75);
  const PoseManifold m;
  for (int trial = 0; trial < 10; ++trial) {
    const ConstraintList list = test::RandomConstraints(rng, 30);
    const PlaneExtrinsicFactor inner(list, 0.02);
    const PoseBlock pose0 = test::RandomPose(rng);
    const PoseBlock ext0 = Near(rng, PoseBlock(Pose3()), 0.05);
    const HeldDirections V0 = RandomHeld(rng, 1 + trial % 3), V1 = RandomHeld(rng, 1 + trial % 2);
    const PoseProjectedFactor f(&inner, {{0, pose0, V0}, {1, ext0, V1}});
    const auto x = test::ToVector(Near(rng, pose0, 0.05));
    const auto e = test::ToVector(Near(rng, ext0, 0.05));
    const Eigen::VectorXd r = test::EvaluateCost(f, {x, e});
    const PoseBlock::Tangent d0 = Minus(PoseBlock::FromArray(x.data()), pose0);
    const PoseBlock::Tangent d1 = Minus(PoseBlock::FromArray(e.data()), ext0);
    const Eigen::VectorXd along0 = V0 * Eigen::VectorXd::Random(V0.cols());
    const Eigen::VectorXd along1 = V1 * Eigen::VectorXd::Random(V1.cols());
    const auto x_moved = test::ToVector(Plus(pose0, d0 + 0.3 * along0));
    const auto e_moved = test::ToVector(Plus(ext0, d1 + 0.3 * along1));
    const Eigen::VectorXd r_moved = test::EvaluateCost(f, {x_moved, e_moved});
    EXPECT_LT((r_moved - r).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, r.norm())) << trial;
    // Not constant across: the inner factor of the projected poses.
    const Eigen::VectorXd r_inner = test::EvaluateCost(
        inner, {test::ToVector(f.Projected(PoseBlock::FromArray(x.data()))),
                test::ToVector(Plus(ext0, d1 - V1 * (V1.transpose() * d1)))});
    EXPECT_LT((r - r_inner).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, r.norm())) << trial;
    EXPECT_LT(test::TangentJacobianError(f, {x, e}, {&m, &m}), 1e-5) << trial;
    std::vector<test::RowMajorMatrix> J;
    test::EvaluateCost(f, {x, e}, &J);
    test::RowMajorMatrix J1(f.num_residuals(), PoseBlock::kNumParams);
    Eigen::VectorXd r_held(f.num_residuals());
    const double* params[2] = {x.data(), e.data()};
    double* jacobians[2] = {nullptr, J1.data()};
    ASSERT_TRUE(f.Evaluate(params, r_held.data(), jacobians));
    EXPECT_EQ(r_held, r);
    EXPECT_LT((J1 - J[1]).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, J[1].cwiseAbs().maxCoeff()));
  }
}

TEST(PoseProjectedFactor, NoHeldDirectionIsTheInnerFactor) {
  std::mt19937 rng(74);
  const ConstraintList list = test::RandomConstraints(rng, 30);
  const PoseBlock pose0 = test::RandomPose(rng);
  const PlaneSummaryFactor inner(list, Pose3(), 0.02, pose0.p_world_imu);
  const PoseProjectedFactor f(&inner, pose0, HeldDirections(6, 0));
  const auto x = test::ToVector(Near(rng, pose0, 0.3));
  std::vector<test::RowMajorMatrix> J, J_inner;
  const Eigen::VectorXd r = test::EvaluateCost(f, {x}, &J);
  const Eigen::VectorXd r_inner = test::EvaluateCost(inner, {x}, &J_inner);
  EXPECT_LT((r - r_inner).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, r_inner.norm()));
  EXPECT_LT((J[0] - J_inner[0]).cwiseAbs().maxCoeff(), 1e-8 * J_inner[0].cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace rvlio

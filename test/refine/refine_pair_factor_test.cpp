// ScanPairPlaneFactor: equals PlaneFactor while the plane's scan stays where
// it was associated, moves the plane with that scan otherwise, and its
// analytic Jacobians match numeric ones through PoseManifold.
// ScanPairSummaryFactor: the same cost, gradient and Gauss-Newton Hessian as
// ScanPairPlaneFactor at random pose pairs away from the association.
#include <memory>
#include <vector>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/plane_factor.h"
#include "rvlio/refine/pair_factor.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

// The constraints of a box-room scan at T_k (world planes), attached to scan
// j at T_j0.
template <class Factor = ScanPairPlaneFactor>
Factor* MakePair(const ConstraintList& list, const Pose3& T_imu_lidar, const Pose3& T_j0,
                 double sigma) {
  auto* f = new Factor;
  const Pose3 T_j0_inv = T_j0.Inverse();
  for (const Constraint& c : list)
    f->Add(T_imu_lidar * c.p_lidar, T_j0.R.transpose() * c.normal_world, T_j0_inv * c.q_world,
           c.weight, sigma);
  f->Finalize();
  return f;
}

TEST(ScanPairPlaneFactor, EqualsPlaneFactorAtTheAssociationPoseOfTheOtherScan) {
  std::mt19937 rng(21);
  const Pose3 T_imu_lidar(test::Rz(0.2), Vector3d(0.1, 0.0, -0.1));
  for (int trial = 0; trial < 10; ++trial) {
    const PoseBlock k_true = test::RandomPose(rng);
    PoseBlock k_true_small(k_true.q_world_imu, 0.5 * k_true.p_world_imu);  // inside the room
    ConstraintList list = test::BoxRoomScan(rng, k_true_small.ToPose3(), T_imu_lidar, 50);
    for (auto& c : list) c.weight = 0.2 + (rng() % 100) / 100.0;
    const PoseBlock j0 = test::RandomPose(rng);
    std::unique_ptr<ScanPairPlaneFactor> pair(MakePair(list, T_imu_lidar, j0.ToPose3(), 0.03));
    PlaneFactor plane(list, T_imu_lidar, 0.03);
    Eigen::Matrix<double, 6, 1> d;
    d << test::RandomVector(rng, 0.05), test::RandomVector(rng, 0.2);
    const PoseBlock k = Plus(k_true_small, d);
    const Eigen::VectorXd r_pair = test::EvaluateCost(*pair, {test::ToVector(k), test::ToVector(j0)});
    const Eigen::VectorXd r_plane = test::EvaluateCost(plane, {test::ToVector(k)});
    ASSERT_GT(r_plane.norm(), 1.0);
    EXPECT_LT((r_pair - r_plane).cwiseAbs().maxCoeff(), 1e-9);
    // Moving k and j together by the same rigid motion leaves r unchanged.
    const Pose3 G(test::Rz(0.7) * test::Rx(-0.3), Vector3d(1, -2, 0.5));
    const PoseBlock kG(G * k.ToPose3()), jG(G * j0.ToPose3());
    const Eigen::VectorXd r_moved = test::EvaluateCost(*pair, {test::ToVector(kG), test::ToVector(jG)});
    EXPECT_LT((r_moved - r_pair).cwiseAbs().maxCoeff(), 1e-9);
  }
}

TEST(ScanPairPlaneFactor, JacobiansMatchNumericDifferences) {
  std::mt19937 rng(5);
  const Pose3 T_imu_lidar(test::Ry(0.1), Vector3d(0.0, 0.2, 0.1));
  PoseManifold manifold;
  for (int trial = 0; trial < 20; ++trial) {
    const PoseBlock k = test::RandomPose(rng);
    PoseBlock k_in(k.q_world_imu, 0.5 * k.p_world_imu);
    ConstraintList list = test::BoxRoomScan(rng, k_in.ToPose3(), T_imu_lidar, 30);
    const PoseBlock j0 = test::RandomPose(rng);
    std::unique_ptr<ScanPairPlaneFactor> f(MakePair(list, T_imu_lidar, j0.ToPose3(), 0.05));
    Eigen::Matrix<double, 6, 1> d;
    d << test::RandomVector(rng, 0.1), test::RandomVector(rng, 0.3);
    const PoseBlock j = Plus(j0, d);
    const double err = test::TangentJacobianError(
        *f, {test::ToVector(k_in), test::ToVector(j)}, {&manifold, &manifold});
    EXPECT_LT(err, 1e-6) << "trial " << trial;
  }
}

// 1/2 |r|^2, the gradient J^T r and the Gauss-Newton Hessian J^T J over the
// tangent spaces of both poses (12 x 12).
struct Quadratic {
  double cost = 0.0;
  Eigen::Matrix<double, 12, 1> gradient;
  Eigen::Matrix<double, 12, 12> hessian;
};

Quadratic TangentQuadratic(const ceres::CostFunction& f, const PoseBlock& k, const PoseBlock& j) {
  PoseManifold manifold;
  std::vector<test::RowMajorMatrix> J_ambient;
  const std::vector<std::vector<double>> x = {test::ToVector(k), test::ToVector(j)};
  const Eigen::VectorXd r = test::EvaluateCost(f, x, &J_ambient);
  Eigen::MatrixXd J(r.size(), 12);
  for (int b = 0; b < 2; ++b) {
    test::RowMajorMatrix plus(7, 6);
    manifold.PlusJacobian(x[b].data(), plus.data());
    J.middleCols(6 * b, 6) = J_ambient[b] * plus;
  }
  Quadratic q;
  q.cost = 0.5 * r.squaredNorm();
  q.gradient = J.transpose() * r;
  q.hessian = J.transpose() * J;
  return q;
}

TEST(ScanPairSummaryFactor, CostGradientAndHessianEqualTheExactFactor) {
  std::mt19937 rng(77);
  const Pose3 T_imu_lidar(test::Rz(-0.4) * test::Rx(0.1), Vector3d(0.05, -0.1, 0.2));
  for (int trial = 0; trial < 50; ++trial) {
    const PoseBlock k_true = test::RandomPose(rng);
    const PoseBlock k_in(k_true.q_world_imu, 0.5 * k_true.p_world_imu);
    ConstraintList list = test::BoxRoomScan(rng, k_in.ToPose3(), T_imu_lidar, 20 + trial * 20);
    for (auto& c : list) c.weight = 0.05 + (rng() % 100) / 100.0;  // Huber x RV weights
    const PoseBlock j0 = test::RandomPose(rng);
    const double sigma = 0.02 + 0.001 * trial;
    std::unique_ptr<ScanPairPlaneFactor> exact(MakePair(list, T_imu_lidar, j0.ToPose3(), sigma));
    std::unique_ptr<ScanPairSummaryFactor> summary(
        MakePair<ScanPairSummaryFactor>(list, T_imu_lidar, j0.ToPose3(), sigma));
    EXPECT_EQ(summary->num_constraints(), static_cast<int>(list.size()));
    // Away from the association: both poses moved (up to ~0.3 rad, ~1 m).
    Eigen::Matrix<double, 6, 1> dk, dj;
    dk << test::RandomVector(rng, 0.1), test::RandomVector(rng, 0.3);
    dj << test::RandomVector(rng, 0.1), test::RandomVector(rng, 0.3);
    const PoseBlock k = Plus(k_in, dk), j = Plus(j0, dj);
    const Quadratic a = TangentQuadratic(*exact, k, j), b = TangentQuadratic(*summary, k, j);
    ASSERT_GT(a.cost, 1.0) << "trial " << trial;
    EXPECT_NEAR(b.cost, a.cost, 1e-9 * a.cost) << "trial " << trial;
    EXPECT_LT((b.gradient - a.gradient).norm(), 1e-8 * a.gradient.norm()) << "trial " << trial;
    EXPECT_LT((b.hessian - a.hessian).norm(), 1e-8 * a.hessian.norm()) << "trial " << trial;
  }
}

TEST(ScanPairSummaryFactor, JacobiansMatchNumericDifferences) {
  std::mt19937 rng(9);
  const Pose3 T_imu_lidar(test::Ry(0.1), Vector3d(0.0, 0.2, 0.1));
  PoseManifold manifold;
  for (int trial = 0; trial < 20; ++trial) {
    const PoseBlock k = test::RandomPose(rng);
    const PoseBlock k_in(k.q_world_imu, 0.5 * k.p_world_imu);
    ConstraintList list = test::BoxRoomScan(rng, k_in.ToPose3(), T_imu_lidar, 60);
    const PoseBlock j0 = test::RandomPose(rng);
    std::unique_ptr<ScanPairSummaryFactor> f(
        MakePair<ScanPairSummaryFactor>(list, T_imu_lidar, j0.ToPose3(), 0.05));
    Eigen::Matrix<double, 6, 1> d;
    d << test::RandomVector(rng, 0.1), test::RandomVector(rng, 0.3);
    const double err = test::TangentJacobianError(
        *f, {test::ToVector(Plus(k_in, d)), test::ToVector(j0)}, {&manifold, &manifold});
    EXPECT_LT(err, 1e-6) << "trial " << trial;
  }
}

}  // namespace
}  // namespace rvlio

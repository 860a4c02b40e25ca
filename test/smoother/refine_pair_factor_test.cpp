// ScanPairPlaneFactor: equals PlaneFactor while the plane's scan stays where
// it was associated, moves the plane with that scan otherwise, and its
// analytic Jacobians match numeric ones through PoseManifold.
#include <memory>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/smoother/manifolds.h"
#include "rvlio/smoother/plane_factor.h"
#include "rvlio/smoother/refine_pair_factor.h"
#include "smoother_test_util.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

// The constraints of a box-room scan at T_k (world planes), attached to scan
// j at T_j0.
ScanPairPlaneFactor* MakePair(const ConstraintList& list, const Pose3& T_imu_lidar,
                              const Pose3& T_j0, double sigma) {
  auto* f = new ScanPairPlaneFactor;
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

}  // namespace
}  // namespace rvlio

// PlaneSummaryFactor: the 13-residual summary of a scan's point-to-plane
// constraints has PlaneFactor's cost, gradient and Gauss-Newton Hessian at
// every pose (not only at the pose of construction), and an exact Jacobian.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/plane_factor.h"
#include "rvlio/factors/plane_summary_factor.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

// Random weights (as RV and the Huber kernel leave them) and noisy normals.
ConstraintList RandomConstraints(std::mt19937& rng, const PoseBlock& truth,
                                 const Pose3& T_imu_lidar, int n) {
  ConstraintList list = test::BoxRoomScan(rng, truth.ToPose3(), T_imu_lidar, n);
  std::uniform_real_distribution<double> w(0.0, 2.0);
  for (Constraint& c : list) {
    c.weight = w(rng);
    c.normal_world = (c.normal_world + test::RandomVector(rng, 0.05)).normalized();
  }
  return list;
}

struct GaussNewton {
  Eigen::Matrix<double, 6, 6> H;
  Eigen::Matrix<double, 6, 1> g;
  double cost;
};

// J^T J, J^T r (tangent) and |r|^2 of a single-pose cost function.
GaussNewton Linearize(const ceres::CostFunction& cost, const std::vector<double>& pose) {
  std::vector<test::RowMajorMatrix> J;
  const Eigen::VectorXd r = test::EvaluateCost(cost, {pose}, &J);
  PoseManifold manifold;
  test::RowMajorMatrix plus(7, 6);
  manifold.PlusJacobian(pose.data(), plus.data());
  const Eigen::MatrixXd J_t = J[0] * plus;
  return {J_t.transpose() * J_t, J_t.transpose() * r, r.squaredNorm()};
}

TEST(PlaneSummaryFactor, MatchesPlaneFactorAwayFromTheConstructionPose) {
  std::mt19937 rng(7);
  const Pose3 T_imu_lidar(test::Rz(0.4) * test::Ry(-0.2), Vector3d(0.2, 0.05, -0.1));
  for (int trial = 0; trial < 30; ++trial) {
    // A scan far from the origin, as after a long run.
    PoseBlock truth = test::RandomPose(rng);
    truth.p_world_imu += Vector3d(300.0, -120.0, 15.0);
    const ConstraintList list = RandomConstraints(rng, truth, T_imu_lidar, 400);
    const PlaneFactor full(list, T_imu_lidar, 0.03);
    const PlaneSummaryFactor summary(list, T_imu_lidar, 0.03, truth.p_world_imu);
    EXPECT_EQ(summary.num_constraints(), 400);
    Eigen::Matrix<double, 6, 1> d;
    d << test::RandomVector(rng, 0.05), test::RandomVector(rng, 0.3);  // ~3 deg, 30 cm away
    const std::vector<double> x = test::ToVector(Plus(truth, d));
    const GaussNewton a = Linearize(full, x), b = Linearize(summary, x);
    EXPECT_NEAR(b.cost, a.cost, 1e-9 * a.cost) << trial;
    EXPECT_LT((b.g - a.g).norm(), 1e-8 * a.g.norm()) << trial;
    EXPECT_LT((b.H - a.H).norm(), 1e-9 * a.H.norm()) << trial;
  }
}

TEST(PlaneSummaryFactor, JacobianMatchesNumericDifferences) {
  std::mt19937 rng(11);
  const Pose3 T_imu_lidar(test::Rx(0.3), Vector3d(0.1, 0.0, 0.2));
  PoseManifold manifold;
  for (int trial = 0; trial < 20; ++trial) {
    const PoseBlock truth = test::RandomPose(rng);
    const PlaneSummaryFactor summary(RandomConstraints(rng, truth, T_imu_lidar, 100), T_imu_lidar,
                                     0.05, truth.p_world_imu + test::RandomVector(rng, 1.0));
    Eigen::Matrix<double, 6, 1> d;
    d << test::RandomVector(rng, 0.1), test::RandomVector(rng, 0.5);
    // Residual scale ~1e3 (sigma 5 cm): a relative error of 1e-6 is far below
    // any Jacobian mistake (which would be O(1) relative).
    EXPECT_LT(test::TangentJacobianError(summary, {test::ToVector(Plus(truth, d))}, {&manifold}),
              1e-6)
        << trial;
  }
}

TEST(PlaneSummaryFactor, InformationIsTheSumOfOuterProductsAndExactlySymmetric) {
  // The reference: M accumulated as a lower-triangle rank update per
  // constraint, then mirrored (the construction before the fixed-size outer
  // product). Same summation order per entry: equal to rounding (bitwise
  // without fused multiply-add), and the mirror image of itself exactly.
  std::mt19937 rng(19);
  const Pose3 T_imu_lidar(test::Rz(-0.3), Vector3d(0.05, 0.0, 0.1));
  for (int trial = 0; trial < 20; ++trial) {
    const PoseBlock truth = test::RandomPose(rng);
    const ConstraintList list = RandomConstraints(rng, truth, T_imu_lidar, 300);
    const Vector3d center = truth.p_world_imu;
    const PlaneSummaryFactor summary(list, T_imu_lidar, 0.03, center);
    PlaneSummaryFactor::Matrix13d ref = PlaneSummaryFactor::Matrix13d::Zero();
    for (const Constraint& c : list) {
      const double s = std::sqrt(c.weight) / 0.03;
      const Vector3d p_imu = T_imu_lidar * c.p_lidar;
      PlaneSummaryFactor::Vector13d a;
      for (int k = 0; k < 3; ++k) a.segment<3>(3 * k) = s * p_imu(k) * c.normal_world;
      a.segment<3>(9) = s * c.normal_world;
      a(12) = -s * c.normal_world.dot(c.q_world - center);
      ref.selfadjointView<Eigen::Lower>().rankUpdate(a);
    }
    ref = ref.selfadjointView<Eigen::Lower>();
    const PlaneSummaryFactor::Matrix13d& M = summary.information();
    EXPECT_TRUE(M == M.transpose()) << trial;
    EXPECT_LE((M - ref).cwiseAbs().maxCoeff(), 1e-14 * ref.cwiseAbs().maxCoeff()) << trial;
  }
}

TEST(PlaneSummaryFactor, EmptyListHasZeroCost) {
  const PlaneSummaryFactor summary({}, Pose3(), 0.03, Vector3d::Zero());
  std::mt19937 rng(3);
  const Eigen::VectorXd r = test::EvaluateCost(summary, {test::ToVector(test::RandomPose(rng))});
  EXPECT_EQ(r.size(), 13);
  EXPECT_EQ(r.squaredNorm(), 0.0);
}

}  // namespace
}  // namespace rvlio

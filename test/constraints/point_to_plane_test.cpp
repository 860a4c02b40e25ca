#include "rvlio/constraints/point_to_plane.h"

#include <random>

#include <gtest/gtest.h>

#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

Eigen::Vector3d RandomVector(std::mt19937* rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return Eigen::Vector3d(u(*rng), u(*rng), u(*rng));
}

Pose3 RandomPose(std::mt19937* rng, double t_scale) {
  return Pose3(so3::Exp(RandomVector(rng, 3.0)), RandomVector(rng, t_scale));
}

Constraint RandomConstraint(std::mt19937* rng) {
  Constraint c;
  c.p_lidar = RandomVector(rng, 20.0);
  c.normal_world = RandomVector(rng, 1.0).normalized();
  c.q_world = RandomVector(rng, 30.0);
  return c;
}

// Applies the perturbation d (12) in the header's order: right rotations,
// additive translations.
void Perturb(const Eigen::Matrix<double, 12, 1>& d, Pose3* T_world_imu, Pose3* T_imu_lidar) {
  T_world_imu->R = T_world_imu->R * so3::Exp(d.segment<3>(0));
  T_world_imu->t += d.segment<3>(3);
  T_imu_lidar->R = T_imu_lidar->R * so3::Exp(d.segment<3>(6));
  T_imu_lidar->t += d.segment<3>(9);
}

Eigen::Matrix<double, 1, 12> NumericJacobian(const Constraint& c, const Pose3& T_world_imu,
                                             const Pose3& T_imu_lidar) {
  const double h = 1e-6;
  Eigen::Matrix<double, 1, 12> J;
  for (int i = 0; i < 12; ++i) {
    Eigen::Matrix<double, 12, 1> d = Eigen::Matrix<double, 12, 1>::Zero();
    d(i) = h;
    Pose3 a = T_world_imu, b = T_imu_lidar, a2 = T_world_imu, b2 = T_imu_lidar;
    Perturb(d, &a, &b);
    Perturb(-d, &a2, &b2);
    J(i) = (PointToPlaneResidual(c, a, b) - PointToPlaneResidual(c, a2, b2)) / (2 * h);
  }
  return J;
}

TEST(PointToPlane, ResidualIsSignedDistance) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 100; ++trial) {
    const Constraint c = RandomConstraint(&rng);
    const Pose3 T_wi = RandomPose(&rng, 10.0), T_il = RandomPose(&rng, 0.5);
    const Eigen::Vector3d p_world = T_wi.R * (T_il.R * c.p_lidar + T_il.t) + T_wi.t;  // Eq. (3)
    const double r = PointToPlaneResidual(c, T_wi, T_il);
    EXPECT_NEAR(r, c.normal_world.dot(p_world - c.q_world), 1e-9);
    // Moving the point along the normal by r puts it on the plane.
    const Eigen::Vector3d on_plane = p_world - r * c.normal_world;
    EXPECT_NEAR(c.normal_world.dot(on_plane - c.q_world), 0.0, 1e-9);
    EXPECT_DOUBLE_EQ(r, PointToPlaneResidualWithExtrinsics(c, T_wi, T_il));
  }
}

TEST(PointToPlane, JacobianMatchesNumericDifferences) {
  std::mt19937 rng(2);
  double worst = 0.0;
  for (int trial = 0; trial < 500; ++trial) {
    const Constraint c = RandomConstraint(&rng);
    const Pose3 T_wi = RandomPose(&rng, 50.0), T_il = RandomPose(&rng, 1.0);
    Eigen::Matrix<double, 1, 6> J6;
    Eigen::Matrix<double, 1, 12> J12;
    const double r6 = PointToPlaneResidual(c, T_wi, T_il, &J6);
    const double r12 = PointToPlaneResidualWithExtrinsics(c, T_wi, T_il, &J12);
    EXPECT_DOUBLE_EQ(r6, r12);
    const Eigen::Matrix<double, 1, 12> Jn = NumericJacobian(c, T_wi, T_il);
    const double scale = 1.0 + Jn.norm();
    EXPECT_LT((J12 - Jn).norm() / scale, 1e-7) << "analytic " << J12 << "\nnumeric  " << Jn;
    EXPECT_LT((J6 - Jn.leftCols<6>()).norm() / scale, 1e-7);
    EXPECT_EQ(J6, J12.leftCols<6>());
    worst = std::max(worst, (J12 - Jn).norm() / scale);
  }
  RecordProperty("worst_relative_error", std::to_string(worst));
}

// First-order prediction of a finite step: r(x [+] d) ~= r(x) + J d.
TEST(PointToPlane, LinearizationPredictsSmallSteps) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    const Constraint c = RandomConstraint(&rng);
    Pose3 T_wi = RandomPose(&rng, 5.0), T_il = RandomPose(&rng, 0.3);
    Eigen::Matrix<double, 1, 12> J;
    const double r0 = PointToPlaneResidualWithExtrinsics(c, T_wi, T_il, &J);
    Eigen::Matrix<double, 12, 1> d;
    d << RandomVector(&rng, 1e-4), RandomVector(&rng, 1e-3), RandomVector(&rng, 1e-4),
        RandomVector(&rng, 1e-3);
    Perturb(d, &T_wi, &T_il);
    const double r1 = PointToPlaneResidual(c, T_wi, T_il);
    EXPECT_NEAR(r1, r0 + (J * d)(0), 1e-5);
  }
}

}  // namespace
}  // namespace rvlio

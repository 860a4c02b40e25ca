// PositionFactor: analytic Jacobians against numeric differences through the
// pose manifold (one and two pose blocks), and the residual's meaning.
#include <random>

#include <gtest/gtest.h>

#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/position_factor.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

TEST(PositionFactor, OneBlockJacobianMatchesNumeric) {
  std::mt19937 rng(41);
  const PoseManifold pose_manifold;
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix3d W = Eigen::Matrix3d::Random() * 50.0 + Eigen::Matrix3d::Identity() * 100;
    const PositionFactor f(test::RandomVector(rng, 2.0), test::RandomVector(rng, 20.0), W);
    EXPECT_LT(test::TangentJacobianError(f, {test::ToVector(test::RandomPose(rng))},
                                         {&pose_manifold}),
              1e-6)
        << trial;
  }
}

TEST(PositionFactor, TwoBlockJacobiansMatchNumeric) {
  std::mt19937 rng(42);
  const PoseManifold pose_manifold;
  for (int trial = 0; trial < 20; ++trial) {
    const double alpha = (trial + 0.5) / 20.0;
    const PositionFactor f(test::RandomVector(rng, 5.0), test::RandomVector(rng, 20.0),
                           Eigen::Matrix3d::Identity() / 0.01, alpha);
    EXPECT_LT(test::TangentJacobianError(f,
                                         {test::ToVector(test::RandomPose(rng)),
                                          test::ToVector(test::RandomPose(rng))},
                                         {&pose_manifold, &pose_manifold}),
              1e-6)
        << trial;
  }
}

TEST(PositionFactor, ResidualIsTheWhitenedInterpolatedPointError) {
  // IMU at (1, 2, 3) and (3, 2, 3), yawed 90 deg; the point 1 m ahead of the
  // IMU (x body = y world); alpha 0.25: (1.5, 3, 3).
  const Eigen::Quaterniond q(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  PoseBlock a(q, Eigen::Vector3d(1, 2, 3)), b(q, Eigen::Vector3d(3, 2, 3));
  const PositionFactor f(Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1.5, 3, 2.9),
                         Eigen::Matrix3d::Identity() / 0.05, 0.25);
  const std::vector<double> va = test::ToVector(a), vb = test::ToVector(b);
  const double* params[] = {va.data(), vb.data()};
  Eigen::Vector3d r;
  ASSERT_TRUE(f.Evaluate(params, r.data(), nullptr));
  EXPECT_NEAR(r.x(), 0.0, 1e-12);
  EXPECT_NEAR(r.y(), 0.0, 1e-12);
  EXPECT_NEAR(r.z(), 0.1 / 0.05, 1e-12);
  EXPECT_TRUE(f.Predict(params).isApprox(Eigen::Vector3d(1.5, 3, 3), 1e-12));
}



TEST(ZeroVelocityFactor, ResidualAndJacobian) {
  std::mt19937 rng(43);
  const ZeroVelocityFactor f(0.002);
  const std::vector<double> sb = test::ToVector(test::RandomSpeedBias(rng));
  EXPECT_LT(test::TangentJacobianError(f, {sb}, {nullptr}), 1e-6);
  const double* params[] = {sb.data()};
  Eigen::Vector3d r;
  ASSERT_TRUE(f.Evaluate(params, r.data(), nullptr));
  EXPECT_TRUE(r.isApprox(Eigen::Vector3d(sb[0], sb[1], sb[2]) / 0.002));
}

}  // namespace
}  // namespace rvlio

// Smoother parameter blocks: manifold axioms, raw-array views, Plus/Minus
// Jacobians against numeric differences.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/factors/parameter_blocks.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

using Eigen::Quaterniond;
using Eigen::Vector3d;
using Tangent6 = PoseBlock::Tangent;
using Params7 = Eigen::Matrix<double, 7, 1>;

constexpr int kTrials = 1000;

Vector3d RandomVector(std::mt19937& rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return Vector3d(n(rng), n(rng), n(rng));
}

Vector3d RandomRotationVector(std::mt19937& rng, double max_angle) {
  std::uniform_real_distribution<double> u(0.0, max_angle);
  return u(rng) * RandomVector(rng, 1.0).normalized();
}

PoseBlock RandomPose(std::mt19937& rng) {
  return PoseBlock(so3::ExpQuat(RandomRotationVector(rng, M_PI)), RandomVector(rng, 20.0));
}

Tangent6 RandomPoseDelta(std::mt19937& rng, double max_angle) {
  Tangent6 d;
  d << RandomRotationVector(rng, max_angle), RandomVector(rng, 3.0);
  return d;
}

SpeedBiasBlock RandomSpeedBias(std::mt19937& rng) {
  SpeedBiasBlock b;
  b.v_world_imu = RandomVector(rng, 5.0);
  b.bg = RandomVector(rng, 0.01);
  b.ba = RandomVector(rng, 0.1);
  return b;
}

// Same rotation (q or -q) and same position.
double PoseDistance(const PoseBlock& a, const PoseBlock& b) {
  const double dq = std::min((a.q_world_imu.coeffs() - b.q_world_imu.coeffs()).norm(),
                             (a.q_world_imu.coeffs() + b.q_world_imu.coeffs()).norm());
  return std::max(dq, (a.p_world_imu - b.p_world_imu).norm());
}

Params7 ToParams(const PoseBlock& x) {
  Params7 p;
  x.ToArray(p.data());
  return p;
}

TEST(PoseBlock, ArrayLayoutIsQuaternionXyzwThenPosition) {
  const PoseBlock x(Quaterniond(0.5, 0.5, -0.5, 0.5), Vector3d(1, 2, 3));  // w x y z
  const Params7 p = ToParams(x);
  EXPECT_EQ(p, (Params7() << 0.5, -0.5, 0.5, 0.5, 1, 2, 3).finished());
  EXPECT_EQ(PoseDistance(PoseBlock::FromArray(p.data()), x), 0.0);
  EXPECT_LT((x.ToPose3().R - x.q_world_imu.toRotationMatrix()).norm(), 1e-15);
  EXPECT_LT(PoseDistance(PoseBlock(x.ToPose3()), x), 1e-15);
}

TEST(PoseBlock, MinusOfPlusReturnsDelta) {
  std::mt19937 rng(31);
  for (int i = 0; i < kTrials; ++i) {
    const PoseBlock x = RandomPose(rng);
    const Tangent6 d = RandomPoseDelta(rng, M_PI - 1e-6);
    EXPECT_LT((Minus(Plus(x, d), x) - d).cwiseAbs().maxCoeff(), 1e-9);
  }
}

TEST(PoseBlock, PlusOfMinusReturnsTarget) {
  std::mt19937 rng(32);
  for (int i = 0; i < kTrials; ++i) {
    const PoseBlock x = RandomPose(rng);
    const PoseBlock y = RandomPose(rng);
    EXPECT_LT(PoseDistance(Plus(x, Minus(y, x)), y), 1e-12);
    EXPECT_LT(Minus(x, x).norm(), 1e-15);
  }
}

TEST(PoseBlock, PlusIsRightPerturbationAndKeepsUnitNorm) {
  std::mt19937 rng(33);
  for (int i = 0; i < 100; ++i) {
    const PoseBlock x = RandomPose(rng);
    const Tangent6 d = RandomPoseDelta(rng, 3.0);
    const PoseBlock y = Plus(x, d);
    EXPECT_NEAR(y.q_world_imu.norm(), 1.0, 1e-15);
    const Eigen::Matrix3d R_expected = x.ToPose3().R * so3::Exp(d.head<3>());
    EXPECT_LT((y.ToPose3().R - R_expected).norm(), 1e-13);
    EXPECT_LT((y.p_world_imu - x.p_world_imu - d.tail<3>()).norm(), 1e-13);
  }
}

TEST(PoseBlock, MinusTreatsAntipodalQuaternionsAsEqual) {
  std::mt19937 rng(34);
  const PoseBlock x = RandomPose(rng);
  PoseBlock y = x;
  y.q_world_imu.coeffs() *= -1.0;
  EXPECT_LT(Minus(y, x).norm(), 1e-15);
}

TEST(PoseBlock, RawArrayFormsMatchStructForms) {
  std::mt19937 rng(35);
  for (int i = 0; i < 100; ++i) {
    const PoseBlock x = RandomPose(rng), y = RandomPose(rng);
    const Tangent6 d = RandomPoseDelta(rng, 3.0);
    const Params7 px = ToParams(x), py = ToParams(y);
    Params7 out;
    PoseBlock::Plus(px.data(), d.data(), out.data());
    EXPECT_EQ(out, ToParams(Plus(x, d)));
    Tangent6 diff;
    PoseBlock::Minus(py.data(), px.data(), diff.data());
    EXPECT_EQ(diff, Minus(y, x));
    PoseBlock::PlusJacobianMatrix Jp;
    PoseBlock::PlusJacobian(px.data(), Jp.data());
    EXPECT_EQ(Jp, PlusJacobian(x));
    PoseBlock::MinusJacobianMatrix Jm;
    PoseBlock::MinusJacobian(px.data(), Jm.data());
    EXPECT_EQ(Jm, MinusJacobian(x));
  }
}

TEST(PoseBlock, PlusJacobianMatchesNumeric) {
  std::mt19937 rng(36);
  const double h = 1e-6;
  for (int i = 0; i < kTrials; ++i) {
    const PoseBlock x = RandomPose(rng);
    PoseBlock::PlusJacobianMatrix J_num;
    for (int k = 0; k < PoseBlock::kTangentDim; ++k) {
      const Tangent6 e = h * Tangent6::Unit(k);
      J_num.col(k) = (ToParams(Plus(x, e)) - ToParams(Plus(x, -e))) / (2 * h);
    }
    EXPECT_LT((PlusJacobian(x) - J_num).cwiseAbs().maxCoeff(), 1e-8);
  }
}

TEST(PoseBlock, MinusJacobianMatchesNumericAndInvertsPlusJacobian) {
  // d Minus(y, x) / d y at y = x, differentiated along the 7 raw parameters.
  std::mt19937 rng(37);
  const double h = 1e-6;
  for (int i = 0; i < kTrials; ++i) {
    const PoseBlock x = RandomPose(rng);
    const Params7 px = ToParams(x);
    PoseBlock::MinusJacobianMatrix J_num;
    for (int k = 0; k < PoseBlock::kNumParams; ++k) {
      const Params7 e = h * Params7::Unit(k);
      Tangent6 plus, minus;
      const Params7 yp = px + e, ym = px - e;
      PoseBlock::Minus(yp.data(), px.data(), plus.data());
      PoseBlock::Minus(ym.data(), px.data(), minus.data());
      J_num.col(k) = (plus - minus) / (2 * h);
    }
    const PoseBlock::MinusJacobianMatrix Jm = MinusJacobian(x);
    EXPECT_LT((Jm - J_num).cwiseAbs().maxCoeff(), 1e-8);
    EXPECT_LT((Jm * PlusJacobian(x) - Eigen::Matrix<double, 6, 6>::Identity()).norm(), 1e-14);
  }
}

TEST(SpeedBiasBlock, ArrayLayoutAndAxioms) {
  std::mt19937 rng(38);
  for (int i = 0; i < kTrials; ++i) {
    const SpeedBiasBlock x = RandomSpeedBias(rng), y = RandomSpeedBias(rng);
    double a[SpeedBiasBlock::kNumParams];
    x.ToArray(a);
    EXPECT_EQ(Vector3d(a[0], a[1], a[2]), x.v_world_imu);
    EXPECT_EQ(Vector3d(a[3], a[4], a[5]), x.bg);
    EXPECT_EQ(Vector3d(a[6], a[7], a[8]), x.ba);
    const SpeedBiasBlock back = SpeedBiasBlock::FromArray(a);
    EXPECT_EQ(Minus(back, x), SpeedBiasBlock::Tangent::Zero());

    SpeedBiasBlock::Tangent d;
    for (int k = 0; k < 9; ++k) d(k) = std::normal_distribution<double>(0.0, 1.0)(rng);
    EXPECT_LT((Minus(Plus(x, d), x) - d).cwiseAbs().maxCoeff(), 1e-12);
    const SpeedBiasBlock z = Plus(x, Minus(y, x));
    EXPECT_LT((z.v_world_imu - y.v_world_imu).norm() + (z.bg - y.bg).norm() + (z.ba - y.ba).norm(),
              1e-12);
  }
}

}  // namespace
}  // namespace rvlio

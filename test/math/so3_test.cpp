// SO(3) maps and Jacobians: closed forms against numeric differences and
// edge cases of Log near 0 and near pi.
#include <cmath>
#include <functional>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using so3::Exp;
using so3::Log;

constexpr int kSo3Trials = 1000;

Vector3d RandomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector3d v(n(rng), n(rng), n(rng));
  return v.normalized();
}

// A rotation vector with angle uniform in [0, max_angle).
Vector3d RandomSo3Vector(std::mt19937& rng, double max_angle) {
  std::uniform_real_distribution<double> u(0.0, max_angle);
  return u(rng) * RandomUnit(rng);
}

// Central differences of f: R^3 -> R^3.
Matrix3d NumericJacobian(const std::function<Vector3d(const Vector3d&)>& f, double h = 1e-6) {
  Matrix3d J;
  for (int i = 0; i < 3; ++i) {
    const Vector3d e = h * Vector3d::Unit(i);
    J.col(i) = (f(e) - f(-e)) / (2.0 * h);
  }
  return J;
}

double RotationDistance(const Matrix3d& A, const Matrix3d& B) { return (A - B).norm(); }

TEST(So3, HatIsCrossProductAndVeeInvertsIt) {
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0.0, 3.0);
  for (int i = 0; i < kSo3Trials; ++i) {
    const Vector3d w(n(rng), n(rng), n(rng)), v(n(rng), n(rng), n(rng));
    EXPECT_LT((so3::Hat(w) * v - w.cross(v)).norm(), 1e-12);
    EXPECT_LT((so3::Vee(so3::Hat(w)) - w).norm(), 1e-15);
    EXPECT_LT((so3::Hat(w) + so3::Hat(w).transpose()).norm(), 1e-15);
  }
}

TEST(So3, ExpIsRotationAndMatchesEigenAngleAxis) {
  std::mt19937 rng(2);
  for (int i = 0; i < kSo3Trials; ++i) {
    const Vector3d w = RandomSo3Vector(rng, 3.0 * M_PI);
    const Matrix3d R = Exp(w);
    EXPECT_LT((R.transpose() * R - Matrix3d::Identity()).norm(), 1e-14);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
    const Matrix3d R_ref = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
    EXPECT_LT(RotationDistance(R, R_ref), 1e-14);
  }
}

TEST(So3, ExpSmallAnglesAgreeWithSeries) {
  // Exp(w) = I + W + W^2/2 + W^3/6 + O(|w|^4): exact to rounding for |w| <= 1e-5.
  std::mt19937 rng(3);
  for (double angle : {0.0, 1e-12, 1e-10, 1e-8, 1e-6, 1e-5, 9.99e-4, 1e-3, 1.001e-3}) {
    const Vector3d w = angle * RandomUnit(rng);
    const Matrix3d W = so3::Hat(w);
    const Matrix3d series = Matrix3d::Identity() + W + W * W / 2.0 + W * W * W / 6.0;
    EXPECT_LT(RotationDistance(Exp(w), series), 1e-15 + std::pow(angle, 4)) << angle;
  }
}

TEST(So3, LogInvertsExpBelowPi) {
  std::mt19937 rng(4);
  for (int i = 0; i < kSo3Trials; ++i) {
    const Vector3d w = RandomSo3Vector(rng, M_PI - 1e-6);
    EXPECT_LT((Log(Exp(w)) - w).norm(), 1e-12) << w.transpose();
  }
}

TEST(So3, ExpInvertsLogForRandomRotations) {
  std::mt19937 rng(5);
  for (int i = 0; i < kSo3Trials; ++i) {
    const Matrix3d R = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    const Vector3d w = Log(R);
    EXPECT_LE(w.norm(), M_PI + 1e-12);
    EXPECT_LT(RotationDistance(Exp(w), R), 1e-13);
  }
}

TEST(So3, LogOfIdentityIsZero) {
  EXPECT_EQ(Log(Matrix3d::Identity()), Vector3d::Zero());
  EXPECT_EQ(so3::LogQuat(Eigen::Quaterniond::Identity()), Vector3d::Zero());
  EXPECT_EQ(Exp(Vector3d::Zero()), Matrix3d::Identity());
}

TEST(So3, LogSmallAnglesKeepRelativeAccuracy) {
  std::mt19937 rng(6);
  for (double angle : {1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5}) {
    for (int i = 0; i < 50; ++i) {
      const Vector3d w = angle * RandomUnit(rng);
      const Vector3d w_back = Log(Exp(w));
      // The matrix entries carry ~1e-16 absolute rounding, so the recovered
      // vector is accurate to that absolute level.
      EXPECT_LT((w_back - w).norm(), 1e-15) << angle;
      EXPECT_LT((w_back - w).norm() / angle, 1e-5) << angle;
    }
  }
}

TEST(So3, LogNearPi) {
  std::mt19937 rng(7);
  for (double gap : {1e-9, 1e-7, 1e-5, 1e-3}) {
    for (int i = 0; i < 50; ++i) {
      const Vector3d w = (M_PI - gap) * RandomUnit(rng);
      const Vector3d w_back = Log(Exp(w));
      EXPECT_LT((w_back - w).norm(), 1e-12) << "gap " << gap;
      EXPECT_LT(RotationDistance(Exp(w_back), Exp(w)), 1e-14);
    }
  }
}

TEST(So3, LogExactlyPiAboutSeveralAxes) {
  std::mt19937 rng(8);
  std::vector<Vector3d> axes = {Vector3d::UnitX(),
                                Vector3d::UnitY(),
                                Vector3d::UnitZ(),
                                Vector3d(1, 1, 0).normalized(),
                                Vector3d(1, -1, 1).normalized(),
                                Vector3d(0, -2, 1).normalized()};
  for (int i = 0; i < 20; ++i) axes.push_back(RandomUnit(rng));
  for (const Vector3d& axis : axes) {
    // A rotation by pi written exactly: R = 2 a a^T - I.
    const Matrix3d R = 2.0 * axis * axis.transpose() - Matrix3d::Identity();
    const Vector3d w = Log(R);
    EXPECT_NEAR(w.norm(), M_PI, 1e-12) << axis.transpose();
    EXPECT_NEAR(std::abs(w.normalized().dot(axis)), 1.0, 1e-12) << axis.transpose();
    EXPECT_LT(RotationDistance(Exp(w), R), 1e-14) << axis.transpose();
    // And through Exp, whose sin(pi) is not exactly zero.
    EXPECT_LT(RotationDistance(Exp(Log(Exp(M_PI * axis))), Exp(M_PI * axis)), 1e-14);
  }
}

TEST(So3, QuaternionExpLogAgreeWithMatrixForms) {
  std::mt19937 rng(9);
  for (int i = 0; i < kSo3Trials; ++i) {
    const Vector3d w = RandomSo3Vector(rng, M_PI - 1e-6);
    const Eigen::Quaterniond q = so3::ExpQuat(w);
    EXPECT_NEAR(q.norm(), 1.0, 1e-15);
    EXPECT_LT(RotationDistance(q.toRotationMatrix(), Exp(w)), 1e-14);
    EXPECT_LT((so3::LogQuat(q) - w).norm(), 1e-12);
    // -q is the same rotation, and LogQuat ignores the scale of q.
    EXPECT_LT((so3::LogQuat(Eigen::Quaterniond(-q.coeffs())) - w).norm(), 1e-12);
    EXPECT_LT((so3::LogQuat(Eigen::Quaterniond(3.5 * q.coeffs())) - w).norm(), 1e-12);
  }
  for (double angle : {1e-12, 1e-9, 1e-6}) {
    const Vector3d w = angle * RandomUnit(rng);
    EXPECT_LT((so3::LogQuat(so3::ExpQuat(w)) - w).norm(), 1e-18 + 1e-12 * angle);
  }
}

TEST(So3, RightJacobianMatchesNumeric) {
  // Exp(w + d) = Exp(w) Exp(Jr(w) d)  =>  Jr = d Log(Exp(w)^T Exp(w + d)) / d d.
  std::mt19937 rng(10);
  for (int i = 0; i < kSo3Trials; ++i) {
    const Vector3d w = RandomSo3Vector(rng, M_PI - 0.1);
    const Matrix3d Rt = Exp(w).transpose();
    const Matrix3d J = NumericJacobian([&](const Vector3d& d) { return Log(Rt * Exp(w + d)); });
    EXPECT_LT((so3::Jr(w) - J).norm(), 1e-8) << w.transpose();
  }
}

TEST(So3, LeftJacobianMatchesNumeric) {
  // Exp(w + d) = Exp(Jl(w) d) Exp(w).
  std::mt19937 rng(11);
  for (int i = 0; i < kSo3Trials; ++i) {
    const Vector3d w = RandomSo3Vector(rng, M_PI - 0.1);
    const Matrix3d Rt = Exp(w).transpose();
    const Matrix3d J = NumericJacobian([&](const Vector3d& d) { return Log(Exp(w + d) * Rt); });
    EXPECT_LT((so3::Jl(w) - J).norm(), 1e-8) << w.transpose();
    EXPECT_LT((so3::Jl(w) - so3::Jr(w).transpose()).norm(), 1e-15);
  }
}

TEST(So3, InverseJacobiansMatchNumericAndInvert) {
  // Log(Exp(w) Exp(d)) = w + JrInv(w) d ;  Log(Exp(d) Exp(w)) = w + JlInv(w) d.
  std::mt19937 rng(12);
  for (int i = 0; i < kSo3Trials; ++i) {
    const Vector3d w = RandomSo3Vector(rng, M_PI - 0.1);
    const Matrix3d R = Exp(w);
    const Matrix3d Jri = NumericJacobian([&](const Vector3d& d) { return Log(R * Exp(d)); });
    const Matrix3d Jli = NumericJacobian([&](const Vector3d& d) { return Log(Exp(d) * R); });
    EXPECT_LT((so3::JrInv(w) - Jri).norm(), 1e-7) << w.transpose();
    EXPECT_LT((so3::JlInv(w) - Jli).norm(), 1e-7) << w.transpose();
    EXPECT_LT((so3::JrInv(w) * so3::Jr(w) - Matrix3d::Identity()).norm(), 1e-12);
    EXPECT_LT((so3::JlInv(w) * so3::Jl(w) - Matrix3d::Identity()).norm(), 1e-12);
    EXPECT_LT((so3::LogRightJacobian(R) - Jri).norm(), 1e-7);
  }
}

TEST(So3, JacobiansAreSmoothAcrossTheTaylorSwitch) {
  // Just below, at and above the small-angle switch, and at tiny angles, the
  // closed forms must agree with the series I -+ W/2 + W^2/6 (or /12).
  std::mt19937 rng(13);
  for (double angle : {0.0, 1e-9, 9.999e-4, 1e-3, 1.0001e-3, 2e-3}) {
    const Vector3d w = angle * RandomUnit(rng);
    const Matrix3d W = so3::Hat(w), I = Matrix3d::Identity();
    const double tol = 1e-15 + std::pow(angle, 3);
    EXPECT_LT((so3::Jr(w) - (I - W / 2.0 + W * W / 6.0)).norm(), tol) << angle;
    EXPECT_LT((so3::JrInv(w) - (I + W / 2.0 + W * W / 12.0)).norm(), tol) << angle;
  }
}

TEST(So3, InverseRightJacobianIsFiniteAtPi) {
  const Vector3d w = M_PI * Vector3d(0.0, 0.6, 0.8);
  const Matrix3d Ji = so3::JrInv(w);
  EXPECT_TRUE(Ji.allFinite());
  EXPECT_LT((Ji * so3::Jr(w) - Matrix3d::Identity()).norm(), 1e-12);
}

TEST(So3, ExpTimesVectorJacobianMatchesNumeric) {
  std::mt19937 rng(14);
  std::normal_distribution<double> n(0.0, 2.0);
  for (int i = 0; i < kSo3Trials; ++i) {
    const Vector3d w = RandomSo3Vector(rng, 2.0 * M_PI);
    const Vector3d v(n(rng), n(rng), n(rng));
    const Matrix3d J = NumericJacobian([&](const Vector3d& d) { return Vector3d(Exp(w + d) * v); });
    EXPECT_LT((so3::ExpTimesVectorJacobian(w, v) - J).norm(), 1e-7 * (1.0 + v.norm()));
  }
}

}  // namespace
}  // namespace rvlio

// PoseManifold: manifold axioms, Jacobians against numeric differences, and
// use inside a Ceres problem next to an automatic-differentiation cost.
#include <random>

#include <ceres/autodiff_cost_function.h>
#include <ceres/problem.h>
#include <ceres/rotation.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include "rvlio/factors/manifolds.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using test::RowMajorMatrix;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Vector7d = Eigen::Matrix<double, 7, 1>;

double RotationDistance(const double* a, const double* b) {
  const Eigen::Quaterniond qa(Eigen::Map<const Eigen::Quaterniond>(a).normalized());
  const Eigen::Quaterniond qb(Eigen::Map<const Eigen::Quaterniond>(b).normalized());
  return qa.angularDistance(qb);
}

TEST(PoseManifold, SizesAndPlusMatchPoseBlock) {
  const PoseManifold m;
  EXPECT_EQ(m.AmbientSize(), 7);
  EXPECT_EQ(m.TangentSize(), 6);
  std::mt19937 rng(1);
  for (int trial = 0; trial < 100; ++trial) {
    const auto x = test::ToVector(test::RandomPose(rng));
    Vector6d d;
    d << test::RandomVector(rng, 0.8), test::RandomVector(rng, 1.0);
    Vector7d a, b;
    ASSERT_TRUE(m.Plus(x.data(), d.data(), a.data()));
    PoseBlock::Plus(x.data(), d.data(), b.data());
    EXPECT_EQ(a, b);  // exactly PoseBlock's operation
    // Right perturbation on rotation, world perturbation on position.
    const PoseBlock X = PoseBlock::FromArray(x.data()), A = PoseBlock::FromArray(a.data());
    EXPECT_LT((A.ToPose3().R - X.ToPose3().R * so3::Exp(d.head<3>())).norm(), 1e-12);
    EXPECT_LT((A.p_world_imu - X.p_world_imu - d.tail<3>()).norm(), 1e-12);
  }
}

TEST(PoseManifold, AxiomsHoldOverRandomTrials) {
  const PoseManifold m;
  std::mt19937 rng(2);
  for (int trial = 0; trial < 500; ++trial) {
    const auto x = test::ToVector(test::RandomPose(rng));
    const auto y = test::ToVector(test::RandomPose(rng));
    Vector6d d;
    d << test::RandomVector(rng, 0.8), test::RandomVector(rng, 1.0);
    if (d.head<3>().norm() > 3.0) continue;  // Minus(Plus(x, d), x) == d needs |d_rot| < pi
    Vector6d zero = Vector6d::Zero(), out;
    Vector7d x0, xd, xy;
    m.Plus(x.data(), zero.data(), x0.data());
    EXPECT_LT(RotationDistance(x0.data(), x.data()), 1e-14);
    EXPECT_LT((x0.tail<3>() - Eigen::Map<const Eigen::Vector3d>(x.data() + 4)).norm(), 1e-15);
    m.Minus(x.data(), x.data(), out.data());
    EXPECT_LT(out.norm(), 1e-14);
    m.Plus(x.data(), d.data(), xd.data());
    m.Minus(xd.data(), x.data(), out.data());
    EXPECT_LT((out - d).norm(), 1e-12) << trial;
    m.Minus(y.data(), x.data(), out.data());
    m.Plus(x.data(), out.data(), xy.data());
    EXPECT_LT(RotationDistance(xy.data(), y.data()), 1e-12);
    EXPECT_LT((xy.tail<3>() - Eigen::Map<const Eigen::Vector3d>(y.data() + 4)).norm(), 1e-12);
  }
}

TEST(PoseManifold, JacobiansMatchNumericDifferences) {
  const PoseManifold m;
  std::mt19937 rng(3);
  const double h = 1e-7;
  for (int trial = 0; trial < 100; ++trial) {
    const auto x = test::ToVector(test::RandomPose(rng));
    RowMajorMatrix plus(7, 6), minus(6, 7);
    ASSERT_TRUE(m.PlusJacobian(x.data(), plus.data()));
    ASSERT_TRUE(m.MinusJacobian(x.data(), minus.data()));
    // d Plus(x, d) / d d at d = 0.
    Eigen::MatrixXd plus_num(7, 6);
    for (int i = 0; i < 6; ++i) {
      Vector6d dp = Vector6d::Zero(), dm = Vector6d::Zero();
      dp(i) = h;
      dm(i) = -h;
      Vector7d a, b;
      m.Plus(x.data(), dp.data(), a.data());
      m.Plus(x.data(), dm.data(), b.data());
      plus_num.col(i) = (a - b) / (2 * h);
    }
    EXPECT_LT((plus - plus_num).cwiseAbs().maxCoeff(), 1e-8);
    // d Minus(y, x) / d y at y = x, y moved in its 7 ambient coordinates.
    Eigen::MatrixXd minus_num(6, 7);
    for (int i = 0; i < 7; ++i) {
      std::vector<double> yp = x, ym = x;
      yp[i] += h;
      ym[i] -= h;
      Vector6d a, b;
      m.Minus(yp.data(), x.data(), a.data());
      m.Minus(ym.data(), x.data(), b.data());
      minus_num.col(i) = (a - b) / (2 * h);
    }
    EXPECT_LT((minus - minus_num).cwiseAbs().maxCoeff(), 1e-7);
    EXPECT_LT((minus * plus - Eigen::Matrix<double, 6, 6>::Identity()).norm(), 1e-14);
  }
}

TEST(PoseManifold, TangentToAmbientJacobianChainsBackExactly) {
  const PoseManifold m;
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0.0, 3.0);
  for (int trial = 0; trial < 50; ++trial) {
    const auto x = test::ToVector(test::RandomPose(rng));
    const int rows = 1 + trial % 17;
    Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> J_t(rows, 6);
    for (int i = 0; i < J_t.size(); ++i) J_t.data()[i] = n(rng);
    RowMajorMatrix J_a(rows, 7), plus(7, 6);
    PoseTangentToAmbientJacobian(x.data(), J_t, J_a.data());
    m.PlusJacobian(x.data(), plus.data());
    EXPECT_LT((J_a * plus - J_t).cwiseAbs().maxCoeff(), 1e-13);
  }
}

// r = R^T (p_world - t) - p_body with the quaternion of the 7-vector (Ceres'
// QuaternionRotatePoint wants [w x y z]).
struct PointAlignment {
  PointAlignment(const Eigen::Vector3d& p_world, const Eigen::Vector3d& p_body)
      : p_world_(p_world), p_body_(p_body) {}
  template <typename T>
  bool operator()(const T* pose, T* r) const {
    const T q_inv[4] = {pose[3], -pose[0], -pose[1], -pose[2]};
    const T d[3] = {T(p_world_.x()) - pose[4], T(p_world_.y()) - pose[5],
                    T(p_world_.z()) - pose[6]};
    T body[3];
    ceres::QuaternionRotatePoint(q_inv, d, body);
    for (int i = 0; i < 3; ++i) r[i] = body[i] - T(p_body_(i));
    return true;
  }
  Eigen::Vector3d p_world_, p_body_;
};

TEST(PoseManifold, SolvesAnAutodiffAlignmentProblem) {
  // Because PlusJacobian is the true derivative, automatic differentiation
  // works on poses with this manifold (the VINS-style [I6; 0] lift would not).
  std::mt19937 rng(5);
  const PoseBlock truth = test::RandomPose(rng);
  auto x = test::ToVector(
      Plus(truth, (Vector6d() << test::RandomVector(rng, 0.3), test::RandomVector(rng, 0.5))
                      .finished()));
  ceres::Problem problem;
  for (int i = 0; i < 10; ++i) {
    const Eigen::Vector3d p_body = test::RandomVector(rng, 3.0);
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PointAlignment, 3, 7>(
                                 new PointAlignment(truth.ToPose3() * p_body, p_body)),
                             nullptr, x.data());
  }
  problem.SetManifold(x.data(), new PoseManifold);
  ceres::Solver::Options options;
  options.max_num_iterations = 20;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  const Vector6d err = Minus(PoseBlock::FromArray(x.data()), truth);
  EXPECT_LT(err.norm(), 1e-9) << summary.BriefReport();
}

}  // namespace
}  // namespace rvlio

// The filter-state manifold: boxplus/boxminus axioms and the Jacobian of Eq. (2).
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/math/so3.h"
#include "rvlio/imu/filter_state.h"

namespace rvlio {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using S = FilterState;

constexpr int kStateTrials = 1000;

Vector3d RandomStateVector(std::mt19937& rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return Vector3d(n(rng), n(rng), n(rng));
}

Vector3d RandomStateRotation(std::mt19937& rng, double max_angle) {
  std::uniform_real_distribution<double> u(0.0, max_angle);
  return u(rng) * RandomStateVector(rng, 1.0).normalized();
}

FilterState RandomState(std::mt19937& rng) {
  FilterState x;
  x.R_world_imu = so3::Exp(RandomStateRotation(rng, M_PI));
  x.p_world_imu = RandomStateVector(rng, 50.0);
  x.v_world_imu = RandomStateVector(rng, 5.0);
  x.bg = RandomStateVector(rng, 0.01);
  x.ba = RandomStateVector(rng, 0.1);
  x.R_imu_lidar = so3::Exp(RandomStateRotation(rng, M_PI));
  x.t_imu_lidar = RandomStateVector(rng, 0.3);
  x.g_world = Vector3d(0, 0, -9.81) + RandomStateVector(rng, 0.1);
  return x;
}

// A tangent vector whose two rotation parts are shorter than max_angle.
Vector24d RandomDelta(std::mt19937& rng, double max_angle) {
  Vector24d d;
  for (int i = 0; i < S::kDim; i += 3) d.segment<3>(i) = RandomStateVector(rng, 2.0);
  d.segment<3>(S::kRot) = RandomStateRotation(rng, max_angle);
  d.segment<3>(S::kExtRot) = RandomStateRotation(rng, max_angle);
  return d;
}

// Largest difference between two states, rotations compared as matrices.
double StateDistance(const FilterState& a, const FilterState& b) {
  return std::max({(a.R_world_imu - b.R_world_imu).cwiseAbs().maxCoeff(),
                   (a.p_world_imu - b.p_world_imu).cwiseAbs().maxCoeff(),
                   (a.v_world_imu - b.v_world_imu).cwiseAbs().maxCoeff(),
                   (a.bg - b.bg).cwiseAbs().maxCoeff(), (a.ba - b.ba).cwiseAbs().maxCoeff(),
                   (a.R_imu_lidar - b.R_imu_lidar).cwiseAbs().maxCoeff(),
                   (a.t_imu_lidar - b.t_imu_lidar).cwiseAbs().maxCoeff(),
                   (a.g_world - b.g_world).cwiseAbs().maxCoeff()});
}

TEST(FilterState, OffsetsTileTheTangentSpace) {
  const int offsets[] = {S::kRot, S::kPos,    S::kVel,    S::kBg,
                         S::kBa,  S::kExtRot, S::kExtPos, S::kGrav};
  for (int i = 0; i < 8; ++i) EXPECT_EQ(offsets[i], 3 * i);
  EXPECT_EQ(S::kDim, 24);
}

TEST(FilterState, BoxminusOfBoxplusReturnsDelta) {
  std::mt19937 rng(21);
  for (int i = 0; i < kStateTrials; ++i) {
    const FilterState x = RandomState(rng);
    const Vector24d d = RandomDelta(rng, M_PI - 1e-6);
    EXPECT_LT((Boxminus(Boxplus(x, d), x) - d).cwiseAbs().maxCoeff(), 1e-9);
  }
}

TEST(FilterState, BoxplusOfBoxminusReturnsTarget) {
  std::mt19937 rng(22);
  for (int i = 0; i < kStateTrials; ++i) {
    const FilterState x = RandomState(rng);
    const FilterState y = RandomState(rng);
    EXPECT_LT(StateDistance(Boxplus(x, Boxminus(y, x)), y), 1e-12);
    EXPECT_LT(Boxminus(x, x).norm(), 1e-15);
  }
}

TEST(FilterState, RotationsUseRightPerturbation) {
  std::mt19937 rng(23);
  const FilterState x = RandomState(rng);
  Vector24d d = Vector24d::Zero();
  const Vector3d w(0.1, -0.2, 0.3);
  d.segment<3>(S::kRot) = w;
  d.segment<3>(S::kExtRot) = -w;
  const FilterState y = Boxplus(x, d);
  EXPECT_LT((y.R_world_imu - x.R_world_imu * so3::Exp(w)).norm(), 1e-15);
  EXPECT_LT((y.R_imu_lidar - x.R_imu_lidar * so3::Exp(-w)).norm(), 1e-15);
  EXPECT_EQ(y.p_world_imu, x.p_world_imu);
  EXPECT_EQ(y.g_world, x.g_world);
}

TEST(FilterState, PosesComposeTheComponents) {
  std::mt19937 rng(24);
  const FilterState x = RandomState(rng);
  const Vector3d p_lidar(1.0, -2.0, 0.5);
  const Vector3d expected =
      x.R_world_imu * (x.R_imu_lidar * p_lidar + x.t_imu_lidar) + x.p_world_imu;
  EXPECT_LT((x.T_world_lidar() * p_lidar - expected).norm(), 1e-12);
}

TEST(FilterState, BoxminusJacobianMatchesNumeric) {
  // J = d((x [+] d) [-] x0) / d d at d = 0 (paper Eq. 2).
  std::mt19937 rng(25);
  const double h = 1e-6;
  for (int trial = 0; trial < 200; ++trial) {
    const FilterState x0 = RandomState(rng);
    const FilterState x = Boxplus(x0, RandomDelta(rng, M_PI - 0.2));
    Matrix24d J_num;
    for (int i = 0; i < S::kDim; ++i) {
      const Vector24d e = h * Vector24d::Unit(i);
      J_num.col(i) = (Boxminus(Boxplus(x, e), x0) - Boxminus(Boxplus(x, -e), x0)) / (2 * h);
    }
    const Matrix24d J = BoxminusJacobian(x, x0);
    EXPECT_LT((J - J_num).cwiseAbs().maxCoeff(), 1e-7);
    EXPECT_LT((BoxminusJacobianInverse(x, x0) * J - Matrix24d::Identity()).cwiseAbs().maxCoeff(),
              1e-12);
  }
}

TEST(FilterState, BoxminusJacobianIsIdentityAtTheLinearizationPoint) {
  std::mt19937 rng(26);
  const FilterState x = RandomState(rng);
  EXPECT_LT((BoxminusJacobian(x, x) - Matrix24d::Identity()).norm(), 1e-15);
}

}  // namespace
}  // namespace rvlio

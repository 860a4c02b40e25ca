// The time-offset residual (lidar.estimate_time_offset, both backends): the
// residual Jacobian against numerical differences, and the scan-time pose.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "rvlio/constraints/time_offset_residual.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

FilterState SomeState() {
  FilterState x;
  x.R_world_imu = so3::Exp(Eigen::Vector3d(0.3, -0.2, 1.1));
  x.p_world_imu = Eigen::Vector3d(1.0, -2.0, 0.5);
  x.v_world_imu = Eigen::Vector3d(1.2, -0.4, 0.3);
  x.R_imu_lidar = so3::Exp(Eigen::Vector3d(0.02, 0.01, -0.03));
  x.t_imu_lidar = Eigen::Vector3d(0.05, -0.02, 0.1);
  return x;
}

ScanTimeMotion SomeMotion() {
  ScanTimeMotion m;
  m.gyro_imu = Eigen::Vector3d(0.4, -0.9, 0.7);
  m.acc_world = Eigen::Vector3d(0.5, 1.5, -0.8);
  return m;
}

Constraint SomeConstraint() {
  Constraint c;
  c.p_lidar = Eigen::Vector3d(3.0, -1.0, 2.0);
  c.normal_world = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  c.q_world = Eigen::Vector3d(2.0, 1.0, 3.0);
  return c;
}

// Column j of TimeOffsetJacobian as the error-state (and offset) perturbation.
double ResidualPerturbed(int column, double eps, double dt_s) {
  const FilterState x = SomeState();
  Vector24d d = Vector24d::Zero();
  double dt = dt_s;
  if (column < 3) d(FilterState::kRot + column) = eps;
  else if (column < 6) d(FilterState::kPos + column - 3) = eps;
  else if (column < 9) d(FilterState::kExtRot + column - 6) = eps;
  else if (column < 12) d(FilterState::kExtPos + column - 9) = eps;
  else if (column < 15) d(FilterState::kVel + column - 12) = eps;
  else dt += eps;
  return PointToPlaneResidualWithTimeOffset(SomeConstraint(), Boxplus(x, d), SomeMotion(), dt);
}

TEST(TimeOffsetResidual, JacobianMatchesNumericalDifferences) {
  for (double dt_s : {0.0, 0.08, -0.12}) {
    TimeOffsetJacobian J;
    const double r =
        PointToPlaneResidualWithTimeOffset(SomeConstraint(), SomeState(), SomeMotion(), dt_s, &J);
    EXPECT_NEAR(r, ResidualPerturbed(0, 0.0, dt_s), 1e-12);
    constexpr double kEps = 1e-6;
    for (int j = 0; j < 16; ++j) {
      const double numeric =
          (ResidualPerturbed(j, kEps, dt_s) - ResidualPerturbed(j, -kEps, dt_s)) / (2 * kEps);
      EXPECT_NEAR(J(j), numeric, 1e-7 * std::max(1.0, std::abs(numeric)))
          << "column " << j << " at dt " << dt_s;
    }
  }
}

// To first order a shift dt moves the scan's pose by w dt and v dt.
TEST(TimeOffsetResidual, ScanTimePoseMovesAlongTheMotion) {
  const FilterState x = SomeState();
  const ScanTimeMotion m = SomeMotion();
  EXPECT_TRUE(ScanTimePose(x, m, 0.0).t.isApprox(x.p_world_imu));
  const double dt = 1e-4;
  const Pose3 T = ScanTimePose(x, m, dt);
  EXPECT_TRUE(((T.t - x.p_world_imu) / dt).isApprox(x.v_world_imu, 1e-3));
  EXPECT_TRUE((so3::Log(x.R_world_imu.transpose() * T.R) / dt).isApprox(m.gyro_imu, 1e-9));
}

}  // namespace
}  // namespace rvlio

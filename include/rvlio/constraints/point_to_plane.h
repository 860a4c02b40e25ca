#pragma once
// The point-to-plane residual shared by both estimators (paper Eq. 3,
// docs/design.md "The shared measurement model"):
//
//   p_imu   = R_imu_lidar p_lidar + t_imu_lidar
//   p_world = R_world_imu p_imu + t_world_imu
//   r       = u^T (p_world - q)
//
// with u = Constraint::normal_world (unit) and q = Constraint::q_world.
//
// Jacobians are taken w.r.t. right perturbations of the rotations (the
// paper's boxplus on SO(3), math/so3.h) and additive perturbations of the
// translations:
//   R_world_imu <- R_world_imu Exp(dtheta),  t_world_imu <- t_world_imu + dp,
//   R_imu_lidar <- R_imu_lidar Exp(dphi),    t_imu_lidar <- t_imu_lidar + dt.
// Columns: [dtheta (3), dp (3)] and, extended, [dtheta, dp, dphi, dt].
#include <Eigen/Core>

#include "rvlio/constraints/constraint.h"
#include "rvlio/math/pose.h"

namespace rvlio {

// r of Eq. (3) at the given poses; J (optional) = dr / [dtheta, dp].
double PointToPlaneResidual(const Constraint& c, const Pose3& T_world_imu, const Pose3& T_imu_lidar,
                            Eigen::Matrix<double, 1, 6>* J = nullptr);

// r of Eq. (3); J (optional) = dr / [dtheta, dp, dphi, dt] (extrinsics estimated).
double PointToPlaneResidualWithExtrinsics(const Constraint& c, const Pose3& T_world_imu,
                                          const Pose3& T_imu_lidar,
                                          Eigen::Matrix<double, 1, 12>* J = nullptr);

// Unweighted |r| of a scan's constraints at the given poses: what is left
// after an estimator's update (divergence monitor, odometry/divergence.h).
struct ResidualStats {
  int count = 0;
  double median_abs_m = 0.0;
  double rms_m = 0.0;
};
ResidualStats ComputeResidualStats(const ConstraintList& constraints, const Pose3& T_world_imu,
                                   const Pose3& T_imu_lidar);

}  // namespace rvlio

#pragma once
// All point-to-plane constraints of one scan as one Ceres cost function
// (docs/design.md, "The shared measurement model" and "The backends"). One
// parameter block: the scan's pose (PoseBlock, 7). Extrinsics are fixed
// (constructor argument).
//
// For constraint i (paper Eq. 3, constraints/point_to_plane.h):
//   residual_i = sqrt(weight_i) / sigma * u_i^T (R_world_imu (R_imu_lidar p_i + t_imu_lidar)
//                                                + t_world_imu - q_i)
// with weight_i = Constraint::weight: the caller folds the RV information
// scaling (1/K for SCVs) and the robust-kernel (IRLS) weight into it, because a
// ceres::LossFunction would act on the squared norm of the whole scan, not on
// each point. sigma: point-to-plane noise standard deviation (m).
//
// Jacobian row (tangent [d_rot, d_pos], right perturbation of R_world_imu):
//   sqrt(weight_i) / sigma * [(p_imu x R^T u)^T, u^T]
// reported in the ambient form of factors/manifolds.h (exact through
// PoseManifold).
#include <Eigen/Core>
#include <ceres/cost_function.h>

#include "rvlio/constraints/constraint.h"
#include "rvlio/math/pose.h"

namespace rvlio {

class PlaneFactor final : public ceres::CostFunction {
 public:
  // constraints: non-empty, weights >= 0, unit normals. sigma_m > 0.
  PlaneFactor(const ConstraintList& constraints, const Pose3& T_imu_lidar, double sigma_m);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  int num_constraints() const { return static_cast<int>(scale_.size()); }

 private:
  Eigen::Matrix3Xd p_imu_;   // R_imu_lidar p_lidar + t_imu_lidar, m
  Eigen::Matrix3Xd u_;       // unit normals (world)
  Eigen::VectorXd u_dot_q_;  // u^T q, m
  Eigen::VectorXd scale_;    // sqrt(weight) / sigma, 1/m
};

// The checks of the extrinsic and time-offset plane factors: non-empty, sigma_m > 0, weights >= 0. Returns
// 1 / sigma_m.
double CheckedPlaneInvSigma(const ConstraintList& constraints, double sigma_m);

}  // namespace rvlio

#pragma once
// All point-to-plane constraints of one scan with the LiDAR-IMU extrinsic as
// a second parameter block (smoother.estimate_extrinsics). Blocks: the scan's
// pose T_world_imu and the extrinsic T_imu_lidar, both PoseBlock (7,
// PoseManifold: right perturbation of the rotation, additive translation).
//
// Residual i (paper Eq. 3, constraints/point_to_plane.h):
//   r_i = sqrt(weight_i) / sigma * u_i^T (R_world_imu (R_imu_lidar p_i + t_imu_lidar)
//                                         + t_world_imu - q_i)
// Tangent Jacobian row: sqrt(weight_i) / sigma * the row of
// PointToPlaneResidualWithExtrinsics() ([dtheta, dp | dphi, dt]), reported in
// the ambient form of factors/manifolds.h for both blocks. The cost is
// bilinear in the two rotations, so unlike PlaneSummaryFactor it keeps the
// points (one residual each).
#include <ceres/cost_function.h>

#include "rvlio/constraints/constraint.h"

namespace rvlio {

class PlaneExtrinsicFactor final : public ceres::CostFunction {
 public:
  // constraints: non-empty, weights >= 0, unit normals. sigma_m > 0.
  PlaneExtrinsicFactor(ConstraintList constraints, double sigma_m);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  int num_constraints() const { return static_cast<int>(constraints_.size()); }

 private:
  ConstraintList constraints_;
  double inv_sigma_ = 1.0;
};

}  // namespace rvlio

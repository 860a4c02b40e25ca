#pragma once
// All point-to-plane constraints of one scan summarized exactly in 13
// residuals: the same cost, gradient and Gauss-Newton Hessian as PlaneFactor
// (plane_factor.h) at every pose, at a cost independent of the number of
// points. The sliding window (window.h) uses it for speed.
//
// With p_i = R_imu_lidar p_lidar,i + t_imu_lidar, s_i = sqrt(weight_i) / sigma
// and a centre c (world; the pose's position at construction keeps the
// numbers small), the weighted residual of paper Eq. (3) is linear in
//   z = [vec(R_world_imu) (9, column-major); t_world_imu - c (3); 1]:
//   s_i u_i^T (R p_i + t - q_i) = a_i^T z,
//   a_i = s_i [p_i (x) u_i ; u_i ; -u_i^T (q_i - c)]   ((x): Kronecker, a[j + 3k] = u_j p_k),
// so the scan's cost is sum_i (a_i^T z)^2 = z^T M z with M = sum_i a_i a_i^T
// (13 x 13, positive semi-definite). With M = V L V^T (eigenvalues below a
// relative floor set to zero) the residual is
//   r = L^1/2 V^T z,   |r|^2 = z^T M z,
// and its tangent Jacobian (pose: R Exp(d_rot), t + d_pos) is
//   d r / d d_rot,k = L^1/2 V^T [vec(R Hat(e_k)); 0; 0],   d r / d d_pos = L^1/2 V^T [0; I; 0],
// reported in the ambient form of factors/manifolds.h. Then J^T J and J^T r
// equal those of PlaneFactor, so Ceres takes the same steps.
//
// The rows a_i and the square root are shared with the scan-pair summary of
// batch refinement (ScanPairSummaryFactor, refine/pair_factor.h), whose z is
// the relative pose of two scans instead of one world pose.
#include <Eigen/Core>
#include <ceres/sized_cost_function.h>

#include "rvlio/constraints/constraint.h"
#include "rvlio/math/pose.h"

namespace rvlio {

namespace plane_summary {

using Matrix13d = Eigen::Matrix<double, 13, 13>;
using Vector13d = Eigen::Matrix<double, 13, 1>;

// Adds a a^T to *M (all of it; exactly symmetric) for the row
// a = s [p (x) u; u; -d] (a[j + 3k] = s u_j p_k), whose product with
// z = [vec(R); t; 1] is s (u^T (R p + t) - d).
void AddRow(const Eigen::Vector3d& p, const Eigen::Vector3d& u, double d, double s, Matrix13d* M);

// L^1/2 V^T for M = V L V^T given by its lower triangle (eigenvalues below a
// relative floor of 1e-15 count as zero): (L^1/2 V^T)^T (L^1/2 V^T) = M.
Matrix13d SqrtInformation(const Matrix13d& M_lower);

// Column k (0..2) of d vec(R Exp(d_rot)) / d d_rot at d_rot = 0: vec(R Hat(e_k)).
Eigen::Matrix<double, 9, 1> RightRotationColumn(const Eigen::Matrix3d& R, int k);

// z = [vec(R) (column-major); t - center; 1] of a world pose (R, t).
Vector13d PoseVector(const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                     const Eigen::Vector3d& center);

// dz / d[d_rot, d_pos] for the perturbation (R Exp(d_rot), t + d_pos).
Eigen::Matrix<double, 13, 6> PoseVectorJacobian(const Eigen::Matrix3d& R);

}  // namespace plane_summary

class PlaneSummaryFactor final : public ceres::SizedCostFunction<13, 7> {
 public:
  using Matrix13d = Eigen::Matrix<double, 13, 13>;
  using Vector13d = Eigen::Matrix<double, 13, 1>;

  // constraints: weights >= 0 (may be empty: zero cost). sigma_m > 0.
  // center_world: any point, ideally near the scan (conditioning only).
  PlaneSummaryFactor(const ConstraintList& constraints, const Pose3& T_imu_lidar, double sigma_m,
                     const Eigen::Vector3d& center_world);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  int num_constraints() const { return num_constraints_; }
  const Matrix13d& information() const { return M_; }  // M above
  const Matrix13d& sqrt_information() const { return sqrt_M_; }  // L^1/2 V^T
  const Eigen::Vector3d& center() const { return center_; }

 private:
  Eigen::Vector3d center_;
  Matrix13d M_;
  Matrix13d sqrt_M_;  // L^1/2 V^T
  int num_constraints_ = 0;
};

}  // namespace rvlio

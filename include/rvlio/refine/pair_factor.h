#pragma once
// Point-to-plane constraints of scan k against planes fitted to scan j's
// points, with the plane attached to scan j: it moves with j's pose
// (batch refinement, refine/refine.h).
//
// PlaneFactor (plane_factor.h) holds world-fixed planes: in an alternation of
// "map from the current estimates" and "poses against that map", a drift that
// all scans share is only corrected by the few scans anchored to the fixed
// gauge, round after round (linear convergence, slow for long sequences).
// Attaching each plane to the scan whose points it was fitted to makes every
// round one joint optimization of all poses over the associations.
//
// With the plane expressed in scan j's IMU frame at association time
// (u_j = R_j0^T u, q_j = T_j0^-1 q), constraint i of scan k is
//   x_i  = R_j^T (R_k p_i + t_k - t_j)            (the point in j's IMU frame)
//   r_i  = s_i (u_j^T x_i - u_j^T q_j),  s_i = sqrt(weight_i) / sigma
// which equals PlaneFactor's residual (paper Eq. 3) while T_j = T_j0. Tangent
// Jacobians (right perturbations R Exp(d_rot), additive positions), with
// u_w = R_j u_j:
//   d r / d rot_k = s (p_i x R_k^T u_w)^T,   d r / d pos_k = s u_w^T,
//   d r / d rot_j = s (u_j x x_i)^T,         d r / d pos_j = -s u_w^T,
// reported in the ambient form of factors/manifolds.h.
//
// Parameter blocks: pose_k (7), pose_j (7) (PoseBlock).
#include <vector>

#include <Eigen/Core>
#include <ceres/cost_function.h>
#include <ceres/sized_cost_function.h>

#include "rvlio/math/pose.h"

namespace rvlio {

class ScanPairPlaneFactor final : public ceres::CostFunction {
 public:
  // Accumulate constraints with Add(), then Finalize() before use.
  // `constraints`: how many Add() calls follow, so that the storage is
  // allocated once at its final size (a refine round holds millions of them).
  explicit ScanPairPlaneFactor(int constraints = 0);

  // p_imu_k: the point in scan k's IMU frame (m); u_j: unit normal and q_j: a
  // plane point, both in scan j's IMU frame; weight >= 0; sigma_m > 0.
  void Add(const Eigen::Vector3d& p_imu_k, const Eigen::Vector3d& u_j, const Eigen::Vector3d& q_j,
           double weight, double sigma_m);
  void Finalize();

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  int num_constraints() const { return static_cast<int>(scale_.size()); }

 private:
  std::vector<Eigen::Vector3d> p_imu_, u_j_;
  std::vector<double> u_dot_q_, scale_;
};

// The constraints of ScanPairPlaneFactor summarized exactly in 13 residuals
// (the construction of PlaneSummaryFactor, plane_summary_factor.h): the
// residual above is linear in the relative pose
//   z = [vec(R_j^T R_k) (9, column-major); R_j^T (t_k - t_j); 1],
//   r_i = a_i^T z,  a_i = s_i [p_i (x) u_j,i; u_j,i; -u_j,i^T q_j,i],
// so the pair's cost sum_i r_i^2 = z^T M z, M = sum_i a_i a_i^T, and the
// residual is r = L^1/2 V^T z (M = V L V^T). Its tangent Jacobians, with
// R_jk = R_j^T R_k and t_kj = R_j^T (t_k - t_j):
//   d z / d rot_k,m = [vec(R_jk Hat(e_m)); 0; 0],   d z / d pos_k = [0; R_j^T; 0],
//   d z / d rot_j,m = [vec(-Hat(e_m) R_jk); -Hat(e_m) t_kj; 0],
//   d z / d pos_j = [0; -R_j^T; 0].
// Same cost, gradient and Gauss-Newton Hessian as the exact factor at every
// pose pair (up to rounding); fixed memory (one 13 x 13 matrix) instead of
// 64 B per constraint in the factor and a 14-double Jacobian row in Ceres.
// Parameter blocks: pose_k (7), pose_j (7).
class ScanPairSummaryFactor final : public ceres::SizedCostFunction<13, 7, 7> {
 public:
  using Matrix13d = Eigen::Matrix<double, 13, 13>;

  ScanPairSummaryFactor();

  // As ScanPairPlaneFactor::Add; Finalize() once after the last.
  void Add(const Eigen::Vector3d& p_imu_k, const Eigen::Vector3d& u_j, const Eigen::Vector3d& q_j,
           double weight, double sigma_m);
  void Finalize();

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  int num_constraints() const { return num_constraints_; }

 private:
  Matrix13d m_;  // M's lower triangle while adding, L^1/2 V^T once finalized
  int num_constraints_ = 0;
  bool finalized_ = false;
};

}  // namespace rvlio

#pragma once
// Priors on the states of the sliding window (window/window.h), as Ceres
// cost functions with analytic Jacobians in the convention of
// factors/manifolds.h (tangent Jacobian times MinusJacobian for pose blocks).
//
// StatePriorFactor: a Gaussian prior on one state, blocks pose (7) and
// speed-bias (9):
//   r = W [pose [-] pose0 ; sb - sb0],   W = diag(1/sigma) (15 rows),
// with pose [-] pose0 = (Log(R0^T R), p - p0) (factors/parameter_blocks.h).
// Tangent Jacobian (right perturbation R Exp(d), p + dp):
//   d r / d [d, dp, dsb] = W blockdiag(JrInv(Log(R0^T R)), I3, I9).
// Used on the first state of a run (static initialization, the IESKF's
// initial standard deviations) and when a marginalization fails.
//
// SpeedBiasContinuityFactor: the weak link between two consecutive states
// when there is no IMU factor between them (an IMU gap or a zero interval):
//   r = W (sb_j - sb_i),   W = diag(1/sigma_v, 1/sigma_bg, 1/sigma_ba),
// so velocity and biases stay determined; the poses are left to the scans.
#include <Eigen/Core>
#include <ceres/sized_cost_function.h>

#include "rvlio/factors/parameter_blocks.h"

namespace rvlio {

// Standard deviations of a state prior (all > 0).
struct StatePriorStd {
  double rot = 1e-3;  // rad
  double pos = 1e-3;  // m
  double vel = 0.1;   // m/s
  double bg = 1e-3;   // rad/s
  double ba = 0.05;   // m/s^2
};

class StatePriorFactor final : public ceres::SizedCostFunction<15, 7, 9> {
 public:
  StatePriorFactor(const PoseBlock& pose0, const SpeedBiasBlock& sb0, const StatePriorStd& std);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  const PoseBlock& pose0() const { return pose0_; }
  const SpeedBiasBlock& speed_bias0() const { return sb0_; }

 private:
  PoseBlock pose0_;
  SpeedBiasBlock sb0_;
  Eigen::Matrix<double, 15, 1> inv_sigma_;
};

// PosePriorFactor: a Gaussian prior on one pose block alone:
//   r = W (pose [-] pose0),
// tangent Jacobian W blockdiag(JrInv(Log(R0^T R)), I3). W = diag(1/sigma_rot
// x3, 1/sigma_pos x3) for the LiDAR-IMU extrinsic (smoother.estimate_extrinsics);
// a general square-root information W (rank-deficient allowed) for the
// degeneracy priors of the smoother and refine (degeneracy/degeneracy.h).
class PosePriorFactor final : public ceres::SizedCostFunction<6, 7> {
 public:
  using Matrix6d = Eigen::Matrix<double, 6, 6>;

  PosePriorFactor(const PoseBlock& pose0, double sigma_rot, double sigma_pos);
  PosePriorFactor(const PoseBlock& pose0, const Matrix6d& sqrt_information);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  PoseBlock pose0_;
  Matrix6d sqrt_information_;
};

class SpeedBiasContinuityFactor final : public ceres::SizedCostFunction<9, 9, 9> {
 public:
  // sigma_v m/s, sigma_bg rad/s, sigma_ba m/s^2; all > 0.
  SpeedBiasContinuityFactor(double sigma_v, double sigma_bg, double sigma_ba);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Matrix<double, 9, 1> inv_sigma_;
};

}  // namespace rvlio

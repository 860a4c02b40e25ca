#pragma once
// IMU preintegration factor between two consecutive scan states (Forster et
// al. 2017, Eq. 45 and Appendix; docs/design.md "The backends").
//
// Parameter blocks: pose_i (7), speed_bias_i (9), pose_j (7), speed_bias_j (9)
// (factors/parameter_blocks.h). With the deltas of `preintegration` corrected to
// first order for the biases at i (ImuPreintegration::Corrected), dt and
// g = g_world:
//   r_R  = Log(dR(b_i)^T R_i^T R_j)
//   r_v  = R_i^T (v_j - v_i - g dt) - dv(b_i)
//   r_p  = R_i^T (p_j - p_i - v_i dt - g dt^2 / 2) - dp(b_i)
//   r_bg = b_g,j - b_g,i
//   r_ba = b_a,j - b_a,i
// residual = S [r_R r_v r_p r_bg r_ba] with S^T S = Sigma^-1 and Sigma =
// blockdiag(preintegration covariance (9x9), gyro and accel bias random-walk
// covariances over dt): the first 9 rows and the bias rows are taken as
// uncorrelated (Forster Eq. 48).
//
// Jacobians are analytic, computed in the tangent spaces (pose: [d_rot, d_pos]
// with R Exp(d_rot), p + d_pos; speed-bias: additive) and reported for the
// 7-dim pose in the ambient form of factors/manifolds.h (J_t MinusJacobian),
// so that they are exact through PoseManifold.
//
// The factor copies the preintegration; when the biases move far, re-integrate
// (ImuPreintegration::Repropagate) and build a new factor.
#include <Eigen/Core>
#include <ceres/sized_cost_function.h>

#include "rvlio/imu/preintegration.h"
#include "rvlio/factors/parameter_blocks.h"

namespace rvlio {

using Matrix15d = Eigen::Matrix<double, 15, 15>;
using Vector15d = Eigen::Matrix<double, 15, 1>;

class ImuFactor final : public ceres::SizedCostFunction<15, 7, 9, 7, 9> {
 public:
  // Residual offsets.
  static constexpr int kR = 0;
  static constexpr int kV = 3;
  static constexpr int kP = 6;
  static constexpr int kBg = 9;
  static constexpr int kBa = 12;

  // preintegration: dt > 0. g_world: gravity in the world frame (m/s^2).
  ImuFactor(ImuPreintegration preintegration, const Eigen::Vector3d& g_world);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  // The residual before whitening, and optionally its tangent-space Jacobians
  // (15x6 per pose, 15x9 per speed-bias block; unwhitened).
  Vector15d Residual(const PoseBlock& pose_i, const SpeedBiasBlock& sb_i, const PoseBlock& pose_j,
                     const SpeedBiasBlock& sb_j,
                     Eigen::Matrix<double, 15, 6>* J_pose_i = nullptr,
                     Eigen::Matrix<double, 15, 9>* J_sb_i = nullptr,
                     Eigen::Matrix<double, 15, 6>* J_pose_j = nullptr,
                     Eigen::Matrix<double, 15, 9>* J_sb_j = nullptr) const;

  const ImuPreintegration& preintegration() const { return preintegration_; }
  const Eigen::Vector3d& g_world() const { return g_world_; }
  const Matrix15d& covariance() const { return covariance_; }
  const Matrix15d& sqrt_information() const { return sqrt_information_; }

 private:
  ImuPreintegration preintegration_;
  Eigen::Vector3d g_world_;
  Matrix15d covariance_;
  Matrix15d sqrt_information_;
};

}  // namespace rvlio

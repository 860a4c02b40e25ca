#include "rvlio/factors/prior_factor.h"

#include "rvlio/common/check.h"
#include "rvlio/math/so3.h"
#include "rvlio/factors/manifolds.h"

namespace rvlio {

StatePriorFactor::StatePriorFactor(const PoseBlock& pose0, const SpeedBiasBlock& sb0,
                                   const StatePriorStd& std)
    : pose0_(pose0), sb0_(sb0) {
  RVLIO_CHECK(std.rot > 0.0 && std.pos > 0.0 && std.vel > 0.0 && std.bg > 0.0 && std.ba > 0.0);
  inv_sigma_ << Eigen::Vector3d::Constant(1.0 / std.rot), Eigen::Vector3d::Constant(1.0 / std.pos),
      Eigen::Vector3d::Constant(1.0 / std.vel), Eigen::Vector3d::Constant(1.0 / std.bg),
      Eigen::Vector3d::Constant(1.0 / std.ba);
}

// r = W [pose [-] pose0 ; sb - sb0]; see the header for the Jacobian.
bool StatePriorFactor::Evaluate(double const* const* parameters, double* residuals,
                                double** jacobians) const {
  const PoseBlock pose = PoseBlock::FromArray(parameters[0]);
  const SpeedBiasBlock sb = SpeedBiasBlock::FromArray(parameters[1]);
  const PoseBlock::Tangent d_pose = Minus(pose, pose0_);
  Eigen::Map<Eigen::Matrix<double, 15, 1>> r(residuals);
  r << d_pose, Minus(sb, sb0_);
  r = r.cwiseProduct(inv_sigma_);
  if (jacobians == nullptr) return true;
  if (jacobians[0] != nullptr) {
    Eigen::Matrix<double, 15, 6, Eigen::RowMajor> J_t = Eigen::Matrix<double, 15, 6>::Zero();
    J_t.block<3, 3>(0, PoseBlock::kRot) = so3::JrInv(d_pose.head<3>());
    J_t.block<3, 3>(3, PoseBlock::kTrans).setIdentity();
    J_t = inv_sigma_.asDiagonal() * J_t;
    PoseTangentToAmbientJacobian(parameters[0], J_t, jacobians[0]);
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 15, 9, Eigen::RowMajor>> J(jacobians[1]);
    J.setZero();
    J.bottomRows<9>() = inv_sigma_.tail<9>().asDiagonal();
  }
  return true;
}

PosePriorFactor::PosePriorFactor(const PoseBlock& pose0, double sigma_rot, double sigma_pos)
    : pose0_(pose0) {
  RVLIO_CHECK(sigma_rot > 0.0 && sigma_pos > 0.0);
  Eigen::Matrix<double, 6, 1> inv_sigma;
  inv_sigma << Eigen::Vector3d::Constant(1.0 / sigma_rot), Eigen::Vector3d::Constant(1.0 / sigma_pos);
  sqrt_information_ = inv_sigma.asDiagonal();
}

PosePriorFactor::PosePriorFactor(const PoseBlock& pose0, const Matrix6d& sqrt_information)
    : pose0_(pose0), sqrt_information_(sqrt_information) {
  RVLIO_CHECK(sqrt_information.allFinite());
}

bool PosePriorFactor::Evaluate(double const* const* parameters, double* residuals,
                               double** jacobians) const {
  const PoseBlock pose = PoseBlock::FromArray(parameters[0]);
  const PoseBlock::Tangent d_pose = Minus(pose, pose0_);
  Eigen::Map<Eigen::Matrix<double, 6, 1>> r(residuals);
  r = sqrt_information_ * d_pose;
  if (jacobians == nullptr || jacobians[0] == nullptr) return true;
  Eigen::Matrix<double, 6, 6, Eigen::RowMajor> J_t = Eigen::Matrix<double, 6, 6>::Zero();
  J_t.block<3, 3>(0, PoseBlock::kRot) = so3::JrInv(d_pose.head<3>());
  J_t.block<3, 3>(3, PoseBlock::kTrans).setIdentity();
  J_t = sqrt_information_ * J_t;
  PoseTangentToAmbientJacobian(parameters[0], J_t, jacobians[0]);
  return true;
}

SpeedBiasContinuityFactor::SpeedBiasContinuityFactor(double sigma_v, double sigma_bg,
                                                     double sigma_ba) {
  RVLIO_CHECK(sigma_v > 0.0 && sigma_bg > 0.0 && sigma_ba > 0.0);
  inv_sigma_ << Eigen::Vector3d::Constant(1.0 / sigma_v), Eigen::Vector3d::Constant(1.0 / sigma_bg),
      Eigen::Vector3d::Constant(1.0 / sigma_ba);
}

// r = W (sb_j - sb_i): Jacobians -W and W.
bool SpeedBiasContinuityFactor::Evaluate(double const* const* parameters, double* residuals,
                                         double** jacobians) const {
  const Eigen::Map<const Eigen::Matrix<double, 9, 1>> sb_i(parameters[0]), sb_j(parameters[1]);
  Eigen::Map<Eigen::Matrix<double, 9, 1>> r(residuals);
  r = inv_sigma_.cwiseProduct(sb_j - sb_i);
  if (jacobians == nullptr) return true;
  for (int k = 0; k < 2; ++k) {
    if (jacobians[k] == nullptr) continue;
    Eigen::Map<Eigen::Matrix<double, 9, 9, Eigen::RowMajor>> J(jacobians[k]);
    J.setZero();
    J.diagonal() = (k == 0 ? -1.0 : 1.0) * inv_sigma_;
  }
  return true;
}

}  // namespace rvlio

#include "rvlio/factors/position_factor.h"

#include "rvlio/common/check.h"
#include "rvlio/factors/manifolds.h"
#include "rvlio/math/so3.h"

namespace rvlio {

PositionFactor::PositionFactor(const Eigen::Vector3d& p_imu_point, const Eigen::Vector3d& z_world,
                               const Eigen::Matrix3d& sqrt_information)
    : p_imu_point_(p_imu_point), z_world_(z_world), sqrt_information_(sqrt_information) {
  set_num_residuals(3);
  mutable_parameter_block_sizes()->push_back(PoseBlock::kNumParams);
}

PositionFactor::PositionFactor(const Eigen::Vector3d& p_imu_point, const Eigen::Vector3d& z_world,
                               const Eigen::Matrix3d& sqrt_information, double alpha)
    : PositionFactor(p_imu_point, z_world, sqrt_information) {
  RVLIO_CHECK(alpha >= 0.0 && alpha <= 1.0);
  alpha_ = alpha;
  blocks_ = 2;
  mutable_parameter_block_sizes()->push_back(PoseBlock::kNumParams);
}

Eigen::Vector3d PositionFactor::Predict(double const* const* parameters) const {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < blocks_; ++i) {
    const PoseBlock pose = PoseBlock::FromArray(parameters[i]);
    const double w = blocks_ == 1 ? 1.0 : (i == 0 ? 1.0 - alpha_ : alpha_);
    p += w * (pose.p_world_imu + pose.q_world_imu * p_imu_point_);
  }
  return p;
}

bool PositionFactor::Evaluate(double const* const* parameters, double* residuals,
                              double** jacobians) const {
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = sqrt_information_ * (Predict(parameters) - z_world_);
  if (jacobians == nullptr) return true;
  for (int i = 0; i < blocks_; ++i) {
    if (jacobians[i] == nullptr) continue;
    const PoseBlock pose = PoseBlock::FromArray(parameters[i]);
    const double w = blocks_ == 1 ? 1.0 : (i == 0 ? 1.0 - alpha_ : alpha_);
    Eigen::Matrix<double, 3, 6, Eigen::RowMajor> J_t;
    J_t.block<3, 3>(0, PoseBlock::kRot) =
        -pose.q_world_imu.toRotationMatrix() * so3::Hat(p_imu_point_);
    J_t.block<3, 3>(0, PoseBlock::kTrans).setIdentity();
    J_t = (w * sqrt_information_) * J_t;
    PoseTangentToAmbientJacobian(parameters[i], J_t, jacobians[i]);
  }
  return true;
}

ZeroVelocityFactor::ZeroVelocityFactor(double sigma_v) : inv_sigma_(1.0 / sigma_v) {
  RVLIO_CHECK(sigma_v > 0.0);
}

bool ZeroVelocityFactor::Evaluate(double const* const* parameters, double* residuals,
                                  double** jacobians) const {
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = inv_sigma_ * Eigen::Map<const Eigen::Vector3d>(parameters[0] + SpeedBiasBlock::kVel);
  if (jacobians == nullptr || jacobians[0] == nullptr) return true;
  Eigen::Map<Eigen::Matrix<double, 3, 9, Eigen::RowMajor>> J(jacobians[0]);
  J.setZero();
  J.block<3, 3>(0, SpeedBiasBlock::kVel) = inv_sigma_ * Eigen::Matrix3d::Identity();
  return true;
}

}  // namespace rvlio

#include "rvlio/factors/pose_projected_factor.h"

#include <vector>

#include "rvlio/common/check.h"
#include "rvlio/factors/manifolds.h"
#include "rvlio/math/so3.h"

namespace rvlio {

namespace {

using TangentJacobian = Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>;
using AmbientJacobian =
    Eigen::Matrix<double, Eigen::Dynamic, PoseBlock::kNumParams, Eigen::RowMajor>;

// blockdiag(J_rot, I3) of a pose tangent map whose rotation part is J_rot.
Eigen::Matrix<double, 6, 6> RotationBlock(const Eigen::Matrix3d& J_rot) {
  Eigen::Matrix<double, 6, 6> J = Eigen::Matrix<double, 6, 6>::Identity();
  J.block<3, 3>(PoseBlock::kRot, PoseBlock::kRot) = J_rot;
  return J;
}

}  // namespace

PoseProjectedFactor::PoseProjectedFactor(const ceres::CostFunction* inner, const PoseBlock& pose0,
                                         const Directions& held)
    : inner_(inner), pose0_(pose0) {
  RVLIO_CHECK(inner != nullptr && !inner->parameter_block_sizes().empty() &&
              inner->parameter_block_sizes()[0] == PoseBlock::kNumParams);
  *mutable_parameter_block_sizes() = inner->parameter_block_sizes();
  set_num_residuals(inner->num_residuals());
  projector_ = Eigen::Matrix<double, 6, 6>::Identity() - held * held.transpose();
}

PoseBlock PoseProjectedFactor::Projected(const PoseBlock& x) const {
  return Plus(pose0_, projector_ * Minus(x, pose0_));
}

bool PoseProjectedFactor::Evaluate(double const* const* parameters, double* residuals,
                                   double** jacobians) const {
  const PoseBlock x = PoseBlock::FromArray(parameters[0]);
  const PoseBlock::Tangent d = Minus(x, pose0_);
  const PoseBlock::Tangent d_proj = projector_ * d;
  double x_proj[PoseBlock::kNumParams];
  Plus(pose0_, d_proj).ToArray(x_proj);
  std::vector<const double*> params(parameters, parameters + parameter_block_sizes().size());
  params[0] = x_proj;
  if (jacobians == nullptr || jacobians[0] == nullptr)
    return inner_->Evaluate(params.data(), residuals, jacobians);
  const int rows = num_residuals();
  AmbientJacobian J_a_proj(rows, PoseBlock::kNumParams);
  std::vector<double*> inner_jacobians(jacobians, jacobians + params.size());
  inner_jacobians[0] = J_a_proj.data();
  if (!inner_->Evaluate(params.data(), residuals, inner_jacobians.data())) return false;
  const TangentJacobian J_t_proj = J_a_proj * PlusJacobian(PoseBlock::FromArray(x_proj));
  const TangentJacobian J_t = J_t_proj * RotationBlock(so3::Jr(d_proj.segment<3>(PoseBlock::kRot))) *
                              projector_ * RotationBlock(so3::JrInv(d.segment<3>(PoseBlock::kRot)));
  PoseTangentToAmbientJacobian(parameters[0], J_t, jacobians[0]);
  return true;
}

}  // namespace rvlio

#include "rvlio/factors/pose_projected_factor.h"

#include <array>
#include <cstdint>
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
    : PoseProjectedFactor(inner, {BlockProjection{0, pose0, held}}) {}

PoseProjectedFactor::PoseProjectedFactor(const ceres::CostFunction* inner,
                                         const std::vector<BlockProjection>& projections)
    : inner_(inner) {
  RVLIO_CHECK(inner != nullptr && !projections.empty() &&
              projections.size() <= static_cast<size_t>(kMaxProjectedBlocks));
  const std::vector<int32_t>& sizes = inner->parameter_block_sizes();
  for (const BlockProjection& b : projections) {
    RVLIO_CHECK(b.block >= 0 && b.block < static_cast<int>(sizes.size()) &&
                sizes[b.block] == PoseBlock::kNumParams);
    for (const Projection& p : projections_) RVLIO_CHECK(p.block != b.block);
    projections_.push_back(
        {b.block, b.pose0, Eigen::Matrix<double, 6, 6>::Identity() - b.held * b.held.transpose()});
  }
  *mutable_parameter_block_sizes() = sizes;
  set_num_residuals(inner->num_residuals());
}

PoseBlock PoseProjectedFactor::Projected(const PoseBlock& x) const {
  const Projection& p = projections_.front();
  return Plus(p.pose0, p.projector * Minus(x, p.pose0));
}

bool PoseProjectedFactor::Evaluate(double const* const* parameters, double* residuals,
                                   double** jacobians) const {
  const size_t n = projections_.size();
  const int rows = num_residuals();
  std::array<PoseBlock::Tangent, kMaxProjectedBlocks> d, d_proj;
  std::array<std::array<double, PoseBlock::kNumParams>, kMaxProjectedBlocks> x_proj;
  std::array<AmbientJacobian, kMaxProjectedBlocks> J_a_proj;
  std::vector<const double*> params(parameters, parameters + parameter_block_sizes().size());
  std::vector<double*> inner_jacobians;
  if (jacobians != nullptr) inner_jacobians.assign(jacobians, jacobians + params.size());
  for (size_t i = 0; i < n; ++i) {
    const Projection& p = projections_[i];
    d[i] = Minus(PoseBlock::FromArray(parameters[p.block]), p.pose0);
    d_proj[i] = p.projector * d[i];
    Plus(p.pose0, d_proj[i]).ToArray(x_proj[i].data());
    params[p.block] = x_proj[i].data();
    if (jacobians != nullptr && jacobians[p.block] != nullptr) {
      J_a_proj[i].resize(rows, PoseBlock::kNumParams);
      inner_jacobians[p.block] = J_a_proj[i].data();
    }
  }
  if (!inner_->Evaluate(params.data(), residuals,
                        jacobians != nullptr ? inner_jacobians.data() : nullptr))
    return false;
  for (size_t i = 0; i < n; ++i) {
    const Projection& p = projections_[i];
    if (jacobians == nullptr || jacobians[p.block] == nullptr) continue;
    const TangentJacobian J_t_proj =
        J_a_proj[i] * PlusJacobian(PoseBlock::FromArray(x_proj[i].data()));
    const TangentJacobian J_t = J_t_proj *
                                RotationBlock(so3::Jr(d_proj[i].segment<3>(PoseBlock::kRot))) *
                                p.projector *
                                RotationBlock(so3::JrInv(d[i].segment<3>(PoseBlock::kRot)));
    PoseTangentToAmbientJacobian(parameters[p.block], J_t, jacobians[p.block]);
  }
  return true;
}

}  // namespace rvlio

#pragma once
// PoseProjectedFactor: a factor on a pose block (and possibly other blocks)
// that has no say along some pose directions: the sliding-window smoother's
// form of solution remapping (degeneracy.method = remap, docs/degeneracy.md
// "Backends"). With V (6 x k, orthonormal columns in the pose tangent
// [dtheta, dp] of factors/parameter_blocks.h) and P = I - V V^T,
//   r(x, y...) = inner(x', y...),   x' = pose0 [+] P (x [-] pose0),
// so the factor is constant along V through pose0: the scan's constraints
// neither pull nor hold the pose there, and the window's other factors (the
// IMU chain, the marginal prior) alone place it, as the IESKF's remapped
// update leaves those directions to the prediction. In every other
// direction the factor is inner unchanged.
// Tangent Jacobian at x (right perturbation), chain rule through x':
//   J_t(x) = J_t'(x') blockdiag(Jr(d'_rot), I3) P blockdiag(JrInv(d_rot), I3),
// d = x [-] pose0, d' = P d, J_t'(x') = J_a'(x') PlusJacobian(x') from inner's
// ambient Jacobian; written back as J_t(x) MinusJacobian(x) (factors/manifolds.h).
// The other blocks' Jacobians are inner's at x'. Does not own inner.
// A factor on two poses (refine's pair factors: a scan's points, another
// scan's planes) can have each pose block projected, each with its own
// pose0 and directions (BlockProjection); the rule above applies per block.
#include <vector>

#include <Eigen/Core>
#include <ceres/cost_function.h>

#include "rvlio/factors/parameter_blocks.h"

namespace rvlio {

class PoseProjectedFactor final : public ceres::CostFunction {
 public:
  using Directions = Eigen::Matrix<double, 6, Eigen::Dynamic>;

  // One pose block of inner projected: its index, pose0 and directions
  // (orthonormal columns, 0..6 of them).
  struct BlockProjection {
    int block = 0;
    PoseBlock pose0;
    Directions held;
  };

  // inner: its first parameter block is a pose (PoseBlock::kNumParams);
  // must outlive this factor. held: orthonormal columns (0..6 of them).
  PoseProjectedFactor(const ceres::CostFunction* inner, const PoseBlock& pose0,
                      const Directions& held);
  // Several pose blocks of inner projected (each index at most once, at most
  // kMaxProjectedBlocks; the first one is what Projected reports).
  static constexpr int kMaxProjectedBlocks = 2;
  PoseProjectedFactor(const ceres::CostFunction* inner,
                      const std::vector<BlockProjection>& projections);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  // x' = pose0 [+] P (x [-] pose0) of the first projected block: the pose
  // the inner factor sees.
  PoseBlock Projected(const PoseBlock& x) const;

 private:
  struct Projection {
    int block;
    PoseBlock pose0;
    Eigen::Matrix<double, 6, 6> projector;  // P = I - V V^T
  };
  const ceres::CostFunction* inner_;
  std::vector<Projection> projections_;
};

}  // namespace rvlio

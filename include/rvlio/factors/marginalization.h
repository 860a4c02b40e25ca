#pragma once
// Marginalization prior (Schur complement), as in VINS-Mono / OKVIS
// (docs/design.md "The backends").
//
// Given the residual blocks f_k connected to the parameter blocks to drop,
// linearized once at the current estimate x0 (tangent-space Jacobians J_k,
// robust losses applied with Ceres' corrector):
//   H = sum J_k^T J_k,  b = sum J_k^T f_k,   ordered [dropped m | kept r],
//   H* = H_rr - H_rm H_mm^+ H_mr,   b* = b_r - H_rm H_mm^+ b_m.
// With H* = V L V^T (eigenvalues below a relative floor set to zero), the
// prior on the kept blocks is the cost 1/2 |S d + S^+T b*|^2 with
//   S = L^1/2 V^T,  S^+T b* = L^-1/2 V^T b*,  d = x [-] x0 (tangent, per block),
// which equals 1/2 d^T H* d + b*^T d + const. Its Jacobian S is fixed at x0
// (first-estimate Jacobians); only d moves with the estimate. For a
// PoseManifold block the Jacobian of d = Minus(x, x0) w.r.t. x's tangent is
// blockdiag(JrInv(d_rot), I) (exact); for other manifolds it is taken as I
// (exact at x0). Euclidean blocks (no manifold) subtract.
//
// Use (window manager):
//   MarginalizationInfo info;
//   info.SetManifold(pose_ptr, &pose_manifold);             // or AddFromProblem()
//   info.AddResidualBlock(cost, loss, {blocks...}, {indices of blocks to drop});
//   ...                                                     // every block touching a dropped one
//   Status s = info.Marginalize();                          // evaluates all costs now
//   auto prior = info.prior();
//   problem.AddResidualBlock(new MarginalizationFactor(prior), nullptr, prior->blocks);
// The cost and loss functions, and the manifolds, are not owned; costs and
// losses must stay alive until Marginalize() returns, manifolds as long as a
// MarginalizationFactor built from the prior is used. The prior copies the
// linearization point, so the window may move its parameter memory afterwards
// (pass the new addresses of the kept blocks, in prior->blocks order).
#include <memory>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>
#include <ceres/cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>

#include "rvlio/common/status.h"

namespace rvlio {

// The Gaussian prior on the kept parameter blocks.
struct MarginalizationPrior {
  std::vector<double*> blocks;                    // kept blocks (addresses when marginalized)
  std::vector<int> ambient_sizes;                 // per kept block
  std::vector<int> tangent_sizes;                 // per kept block
  std::vector<int> tangent_offsets;               // offset of each block in d
  std::vector<const ceres::Manifold*> manifolds;  // nullptr: Euclidean (not owned)
  std::vector<Eigen::VectorXd> x0;                // linearization point (ambient), fixed
  Eigen::MatrixXd S;                              // sqrt of H*, tangent_dim x tangent_dim
  Eigen::VectorXd r0;                             // S^+T b*
  int tangent_dim = 0;
  int rank = 0;                                   // eigenvalues of H* kept above the floor
};

class MarginalizationInfo {
 public:
  struct Options {
    // Eigenvalues below relative_eigenvalue_floor * (largest eigenvalue) are
    // treated as zero, in H_mm^+ and in the square root of H*.
    double relative_eigenvalue_floor = 1e-12;
  };

  MarginalizationInfo() = default;
  explicit MarginalizationInfo(const Options& options) : options_(options) {}

  // One residual block: its cost (and optional loss), its parameter blocks in
  // the cost's order, and the positions (into `blocks`) of those to drop.
  void AddResidualBlock(const ceres::CostFunction* cost, const ceres::LossFunction* loss,
                        const std::vector<double*>& blocks, const std::vector<int>& drop_indices);
  // The manifold of a parameter block (not owned); blocks without are Euclidean.
  void SetManifold(const double* block, const ceres::Manifold* manifold);
  // Every residual block of `problem` that touches one of `drop`, with the
  // problem's cost, loss and manifolds (for all their blocks).
  void AddFromProblem(const ceres::Problem& problem, const std::vector<double*>& drop);

  // Linearizes every residual block at the current parameter values, forms
  // H and b and the Schur complement. Fails (InvalidInput) when nothing is
  // dropped or kept, or when a cost function fails to evaluate.
  Status Marginalize();

  // After a successful Marginalize().
  std::shared_ptr<const MarginalizationPrior> prior() const { return prior_; }
  // The full linear system before the Schur complement (for diagnostics and
  // tests): H, b over the tangent spaces of blocks(), dropped blocks first.
  const Eigen::MatrixXd& H() const { return H_; }
  const Eigen::VectorXd& b() const { return b_; }
  const std::vector<double*>& ordered_blocks() const { return ordered_; }
  int dropped_dim() const { return dropped_dim_; }

 private:
  struct Residual {
    const ceres::CostFunction* cost;
    const ceres::LossFunction* loss;
    std::vector<double*> blocks;
  };
  struct BlockInfo {
    int ambient_size = 0;
    int tangent_size = 0;
    int offset = -1;  // tangent offset in H
    bool drop = false;
    const ceres::Manifold* manifold = nullptr;
  };

  Status OrderBlocks();
  Status Linearize(const Residual& residual);

  Options options_;
  std::vector<Residual> residuals_;
  std::unordered_map<const double*, BlockInfo> info_;
  std::vector<double*> ordered_;
  int dropped_dim_ = 0;
  int total_dim_ = 0;
  Eigen::MatrixXd H_;
  Eigen::VectorXd b_;
  std::shared_ptr<MarginalizationPrior> prior_;
};

// The prior as a Ceres cost: residual S (x [-] x0) + r0 over the kept blocks.
class MarginalizationFactor final : public ceres::CostFunction {
 public:
  explicit MarginalizationFactor(std::shared_ptr<const MarginalizationPrior> prior);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  const MarginalizationPrior& prior() const { return *prior_; }

 private:
  std::shared_ptr<const MarginalizationPrior> prior_;
};

}  // namespace rvlio

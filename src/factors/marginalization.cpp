#include "rvlio/factors/marginalization.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <Eigen/Eigenvalues>

#include "rvlio/common/check.h"
#include "rvlio/math/so3.h"
#include "rvlio/factors/manifolds.h"

namespace rvlio {
namespace {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Ceres' robust-loss corrector (Triggs et al., "Bundle adjustment - a modern
// synthesis", Sec. 4.3; ceres/internal/corrector.cc): with s = |f|^2 and
// rho = [rho(s), rho'(s), rho''(s)],
//   alpha = 1 - sqrt(1 + 2 s rho'' / rho')  (0 when rho'' <= 0 or s = 0),
//   f <- sqrt(rho') / (1 - alpha) f,   J <- sqrt(rho') (I - alpha f f^T / s) J,
// so that J^T J and J^T f are the Gauss-Newton model of rho(|f|^2) / 2.
// Returns false when rho' <= 0 (the block carries no information).
bool ApplyLoss(const ceres::LossFunction& loss, Eigen::VectorXd* f,
               std::vector<RowMajorMatrix>* jacobians) {
  const double s = f->squaredNorm();
  double rho[3];
  loss.Evaluate(s, rho);
  if (!(rho[1] > 0.0)) return false;
  const double sqrt_rho1 = std::sqrt(rho[1]);
  double alpha = 0.0;
  if (s > 0.0 && rho[2] > 0.0) alpha = 1.0 - std::sqrt(1.0 + 2.0 * s * rho[2] / rho[1]);
  for (RowMajorMatrix& J : *jacobians) {
    if (alpha != 0.0) J -= (alpha / s) * (*f) * (f->transpose() * J);
    J *= sqrt_rho1;
  }
  *f *= sqrt_rho1 / (1.0 - alpha);
  return true;
}

// Symmetric eigendecomposition with eigenvalues below floor (relative to the
// largest) set to zero.
struct ClampedEigen {
  Eigen::VectorXd lambda;
  Eigen::MatrixXd V;
  int rank = 0;
};

ClampedEigen Decompose(const Eigen::MatrixXd& A, double relative_floor) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (A + A.transpose()));
  ClampedEigen out;
  out.V = eig.eigenvectors();
  out.lambda = eig.eigenvalues();
  const double floor = relative_floor * std::max(out.lambda.maxCoeff(), 0.0);
  for (int i = 0; i < out.lambda.size(); ++i) {
    if (out.lambda(i) > floor && out.lambda(i) > 0.0) {
      ++out.rank;
    } else {
      out.lambda(i) = 0.0;
    }
  }
  return out;
}

Eigen::VectorXd SafeInverse(const Eigen::VectorXd& x) {
  return x.unaryExpr([](double v) { return v > 0.0 ? 1.0 / v : 0.0; });
}

}  // namespace

void MarginalizationInfo::AddResidualBlock(const ceres::CostFunction* cost,
                                           const ceres::LossFunction* loss,
                                           const std::vector<double*>& blocks,
                                           const std::vector<int>& drop_indices) {
  RVLIO_CHECK(cost != nullptr);
  RVLIO_CHECK(blocks.size() == cost->parameter_block_sizes().size());
  for (size_t k = 0; k < blocks.size(); ++k) {
    BlockInfo& info = info_[blocks[k]];
    const int size = cost->parameter_block_sizes()[k];
    RVLIO_CHECK_MSG(info.ambient_size == 0 || info.ambient_size == size,
                    "a parameter block is used with two different sizes");
    info.ambient_size = size;
  }
  for (int index : drop_indices) {
    RVLIO_CHECK(index >= 0 && index < static_cast<int>(blocks.size()));
    info_[blocks[index]].drop = true;
  }
  residuals_.push_back({cost, loss, blocks});
}

void MarginalizationInfo::SetManifold(const double* block, const ceres::Manifold* manifold) {
  info_[block].manifold = manifold;
}

void MarginalizationInfo::AddFromProblem(const ceres::Problem& problem,
                                         const std::vector<double*>& drop) {
  std::vector<ceres::ResidualBlockId> ids;
  for (double* block : drop) {
    std::vector<ceres::ResidualBlockId> touching;
    problem.GetResidualBlocksForParameterBlock(block, &touching);
    for (ceres::ResidualBlockId id : touching)
      if (std::find(ids.begin(), ids.end(), id) == ids.end()) ids.push_back(id);
  }
  for (ceres::ResidualBlockId id : ids) {
    std::vector<double*> blocks;
    problem.GetParameterBlocksForResidualBlock(id, &blocks);
    std::vector<int> drop_indices;
    for (size_t k = 0; k < blocks.size(); ++k) {
      if (std::find(drop.begin(), drop.end(), blocks[k]) != drop.end())
        drop_indices.push_back(static_cast<int>(k));
      SetManifold(blocks[k], problem.GetManifold(blocks[k]));
    }
    AddResidualBlock(problem.GetCostFunctionForResidualBlock(id),
                     problem.GetLossFunctionForResidualBlock(id), blocks, drop_indices);
  }
}

// Dropped blocks first (in order of appearance), then the kept ones.
Status MarginalizationInfo::OrderBlocks() {
  ordered_.clear();
  for (bool dropped : {true, false})
    for (const Residual& res : residuals_)
      for (double* block : res.blocks) {
        BlockInfo& info = info_[block];
        if (info.drop != dropped || info.offset >= 0) continue;
        info.tangent_size = info.ambient_size;
        if (info.manifold != nullptr) {
          RVLIO_CHECK(info.manifold->AmbientSize() == info.ambient_size);
          info.tangent_size = info.manifold->TangentSize();
        }
        info.offset = 0;  // marks "ordered"; set below
        ordered_.push_back(block);
      }
  int offset = 0;
  dropped_dim_ = 0;
  for (double* block : ordered_) {
    BlockInfo& info = info_[block];
    info.offset = offset;
    offset += info.tangent_size;
    if (info.drop) dropped_dim_ += info.tangent_size;
  }
  total_dim_ = offset;
  if (dropped_dim_ == 0) return Status::InvalidInput("marginalization: no parameter block to drop");
  if (dropped_dim_ == total_dim_)
    return Status::InvalidInput("marginalization: no parameter block is kept");
  return Status::Ok();
}

// Adds J^T J and J^T f of one residual block (tangent Jacobians, loss applied).
Status MarginalizationInfo::Linearize(const Residual& res) {
  const int n = res.cost->num_residuals();
  const size_t num_blocks = res.blocks.size();
  Eigen::VectorXd f(n);
  std::vector<RowMajorMatrix> J_ambient(num_blocks);
  std::vector<double*> J_ptrs(num_blocks);
  for (size_t k = 0; k < num_blocks; ++k) {
    J_ambient[k].resize(n, info_[res.blocks[k]].ambient_size);
    J_ptrs[k] = J_ambient[k].data();
  }
  if (!res.cost->Evaluate(res.blocks.data(), f.data(), J_ptrs.data()) || !f.allFinite())
    return Status::InvalidInput("marginalization: a residual block failed to evaluate");
  if (res.loss != nullptr && !ApplyLoss(*res.loss, &f, &J_ambient)) return Status::Ok();

  std::vector<Eigen::MatrixXd> J(num_blocks);
  for (size_t k = 0; k < num_blocks; ++k) {
    const BlockInfo& info = info_[res.blocks[k]];
    if (info.manifold == nullptr) {
      J[k] = J_ambient[k];
      continue;
    }
    RowMajorMatrix plus(info.ambient_size, info.tangent_size);
    info.manifold->PlusJacobian(res.blocks[k], plus.data());
    J[k] = J_ambient[k] * plus;
  }
  for (size_t a = 0; a < num_blocks; ++a) {
    const BlockInfo& ia = info_[res.blocks[a]];
    b_.segment(ia.offset, ia.tangent_size) += J[a].transpose() * f;
    for (size_t c = 0; c < num_blocks; ++c) {
      const BlockInfo& ic = info_[res.blocks[c]];
      H_.block(ia.offset, ic.offset, ia.tangent_size, ic.tangent_size) +=
          J[a].transpose() * J[c];
    }
  }
  return Status::Ok();
}

Status MarginalizationInfo::Marginalize() {
  for (auto& entry : info_) entry.second.offset = -1;
  Status status = OrderBlocks();
  if (!status.ok()) return status;
  H_ = Eigen::MatrixXd::Zero(total_dim_, total_dim_);
  b_ = Eigen::VectorXd::Zero(total_dim_);
  for (const Residual& res : residuals_) {
    status = Linearize(res);
    if (!status.ok()) return status;
  }
  if (!H_.allFinite() || !b_.allFinite())
    return Status::InvalidInput("marginalization: non-finite linear system");

  // Schur complement of the dropped block.
  const int m = dropped_dim_, r = total_dim_ - dropped_dim_;
  const ClampedEigen mm = Decompose(H_.topLeftCorner(m, m), options_.relative_eigenvalue_floor);
  const Eigen::MatrixXd H_mm_inv =
      mm.V * SafeInverse(mm.lambda).asDiagonal() * mm.V.transpose();
  const Eigen::MatrixXd H_rm_H_mm_inv = H_.bottomLeftCorner(r, m) * H_mm_inv;
  const Eigen::MatrixXd H_star =
      H_.bottomRightCorner(r, r) - H_rm_H_mm_inv * H_.topRightCorner(m, r);
  const Eigen::VectorXd b_star = b_.tail(r) - H_rm_H_mm_inv * b_.head(m);

  // S = L^1/2 V^T, r0 = L^-1/2 V^T b*.
  const ClampedEigen rr = Decompose(H_star, options_.relative_eigenvalue_floor);
  const Eigen::VectorXd sqrt_lambda = rr.lambda.cwiseSqrt();
  auto prior = std::make_shared<MarginalizationPrior>();
  prior->S = sqrt_lambda.asDiagonal() * rr.V.transpose();
  prior->r0 = SafeInverse(sqrt_lambda).asDiagonal() * (rr.V.transpose() * b_star);
  prior->tangent_dim = r;
  prior->rank = rr.rank;
  for (double* block : ordered_) {
    const BlockInfo& info = info_[block];
    if (info.drop) continue;
    prior->blocks.push_back(block);
    prior->ambient_sizes.push_back(info.ambient_size);
    prior->tangent_sizes.push_back(info.tangent_size);
    prior->tangent_offsets.push_back(info.offset - m);
    prior->manifolds.push_back(info.manifold);
    prior->x0.push_back(Eigen::Map<const Eigen::VectorXd>(block, info.ambient_size));
  }
  prior_ = std::move(prior);
  return Status::Ok();
}

MarginalizationFactor::MarginalizationFactor(std::shared_ptr<const MarginalizationPrior> prior)
    : prior_(std::move(prior)) {
  RVLIO_CHECK(prior_ != nullptr && prior_->tangent_dim > 0);
  set_num_residuals(prior_->tangent_dim);
  for (int size : prior_->ambient_sizes) mutable_parameter_block_sizes()->push_back(size);
}

// residual = S d + r0 with d_k = x_k [-] x0_k. Jacobian of block k:
// S[:, k] D_k MinusJacobian(x_k), D_k = d(x [-] x0)/d(tangent at x)
// (blockdiag(JrInv(d_rot), I) for PoseManifold, I otherwise).
bool MarginalizationFactor::Evaluate(double const* const* parameters, double* residuals,
                                     double** jacobians) const {
  const MarginalizationPrior& p = *prior_;
  Eigen::VectorXd d(p.tangent_dim);
  for (size_t k = 0; k < p.blocks.size(); ++k) {
    const int off = p.tangent_offsets[k], ts = p.tangent_sizes[k], as = p.ambient_sizes[k];
    if (p.manifolds[k] != nullptr) {
      if (!p.manifolds[k]->Minus(parameters[k], p.x0[k].data(), d.data() + off)) return false;
    } else {
      d.segment(off, ts) = Eigen::Map<const Eigen::VectorXd>(parameters[k], as) - p.x0[k];
    }
  }
  Eigen::Map<Eigen::VectorXd> residual(residuals, p.tangent_dim);
  residual = p.S * d + p.r0;
  if (jacobians == nullptr) return true;
  for (size_t k = 0; k < p.blocks.size(); ++k) {
    if (jacobians[k] == nullptr) continue;
    const int off = p.tangent_offsets[k], ts = p.tangent_sizes[k], as = p.ambient_sizes[k];
    Eigen::Map<RowMajorMatrix> J(jacobians[k], p.tangent_dim, as);
    if (p.manifolds[k] == nullptr) {
      J = p.S.middleCols(off, ts);
      continue;
    }
    Eigen::MatrixXd J_t = p.S.middleCols(off, ts);
    if (dynamic_cast<const PoseManifold*>(p.manifolds[k]) != nullptr)
      J_t.leftCols<3>() = J_t.leftCols<3>() * so3::JrInv(d.segment<3>(off));
    RowMajorMatrix minus(ts, as);
    if (!p.manifolds[k]->MinusJacobian(parameters[k], minus.data())) return false;
    J = J_t * minus;
  }
  return true;
}

}  // namespace rvlio

#include "rvlio/factors/manifolds.h"

#include "rvlio/common/check.h"
#include "rvlio/factors/parameter_blocks.h"

namespace rvlio {

bool PoseManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  PoseBlock::Plus(x, delta, x_plus_delta);
  return true;
}

bool PoseManifold::PlusJacobian(const double* x, double* jacobian) const {
  PoseBlock::PlusJacobian(x, jacobian);
  return true;
}

bool PoseManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  PoseBlock::Minus(y, x, y_minus_x);
  return true;
}

bool PoseManifold::MinusJacobian(const double* x, double* jacobian) const {
  PoseBlock::MinusJacobian(x, jacobian);
  return true;
}

PoseSubsetManifold::PoseSubsetManifold(const std::array<bool, 6>& free) {
  for (int i = 0; i < 6; ++i)
    if (free[i]) axes_.push_back(i);
  RVLIO_CHECK_MSG(!axes_.empty(), "PoseSubsetManifold needs a free axis");
}

bool PoseSubsetManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  double full[6] = {0, 0, 0, 0, 0, 0};
  for (size_t k = 0; k < axes_.size(); ++k) full[axes_[k]] = delta[k];
  PoseBlock::Plus(x, full, x_plus_delta);
  return true;
}

bool PoseSubsetManifold::PlusJacobian(const double* x, double* jacobian) const {
  Eigen::Matrix<double, 7, 6, Eigen::RowMajor> full;
  PoseBlock::PlusJacobian(x, full.data());
  const int k = TangentSize();
  Eigen::Map<Eigen::Matrix<double, 7, Eigen::Dynamic, Eigen::RowMajor>> J(jacobian, 7, k);
  for (int c = 0; c < k; ++c) J.col(c) = full.col(axes_[c]);
  return true;
}

bool PoseSubsetManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  double full[6];
  PoseBlock::Minus(y, x, full);
  for (size_t k = 0; k < axes_.size(); ++k) y_minus_x[k] = full[axes_[k]];
  return true;
}

bool PoseSubsetManifold::MinusJacobian(const double* x, double* jacobian) const {
  Eigen::Matrix<double, 6, 7, Eigen::RowMajor> full;
  PoseBlock::MinusJacobian(x, full.data());
  const int k = TangentSize();
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor>> J(jacobian, k, 7);
  for (int r = 0; r < k; ++r) J.row(r) = full.row(axes_[r]);
  return true;
}

// MinusJacobian = [M_rot 0; 0 I] with M_rot 3x4, so only the rotation columns
// need a product: J_a[:, 0:4] = J_t[:, 0:3] M_rot, J_a[:, 4:7] = J_t[:, 3:6].
void PoseTangentToAmbientJacobian(
    const double* x,
    const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>>& tangent,
    double* ambient) {
  const PoseBlock::MinusJacobianMatrix M = MinusJacobian(PoseBlock::FromArray(x));
  const Eigen::Matrix<double, 3, 4> M_rot =
      M.block<3, 4>(PoseBlock::kRot, PoseBlock::kQuat);
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor>> J_a(ambient,
                                                                           tangent.rows(), 7);
  J_a.leftCols<4>().noalias() = tangent.leftCols<3>() * M_rot;
  J_a.rightCols<3>() = tangent.rightCols<3>();
}

}  // namespace rvlio

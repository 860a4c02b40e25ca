#include "rvlio/smoother/manifolds.h"

#include "rvlio/math/smoother_blocks.h"

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

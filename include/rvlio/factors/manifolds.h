#pragma once
// ceres::Manifold wrappers of the smoother's parameter blocks
// (factors/parameter_blocks.h).
//
// PoseManifold: PoseBlock, ambient 7 [qx qy qz qw px py pz], tangent 6
// [d_rot, d_pos] with a right perturbation on the rotation and a world-frame
// perturbation on the position:  x [+] d = (q Exp(d_rot), p + d_pos).
// Plus/Minus and both Jacobians are exactly PoseBlock's, so PlusJacobian is the
// true derivative of Plus (7x6) and MinusJacobian (6x7) is its left inverse
// (MinusJacobian(x) PlusJacobian(x) = I).
//
// Jacobian convention of the smoother's cost functions (imu_factor.h,
// plane_factor.h, marginalization.h): a factor computes its Jacobian J_t with
// respect to the 6-dim tangent and reports the ambient Jacobian
//   J_a = J_t MinusJacobian(x)        (rows x 7),
// so that the chain Ceres forms, J_a PlusJacobian(x) = J_t, is exact. Unlike
// the VINS-Mono convention (tangent Jacobian in the first 6 columns and a fake
// PlusJacobian [I6; 0]) this keeps the manifold honest: automatic- or
// numeric-differentiated cost functions and ceres::GradientChecker can be
// mixed with these factors on the same pose blocks.
//
// SpeedBiasBlock is Euclidean (9): use no manifold or ceres::EuclideanManifold<9>.
#include <array>
#include <vector>

#include <Eigen/Core>
#include <ceres/manifold.h>

namespace rvlio {

class PoseManifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 7; }
  int TangentSize() const override { return 6; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

// PoseSubsetManifold: PoseManifold with some tangent axes held fixed (the
// extrinsic axes the motion has not excited yet). Tangent = the free axes e:
//   x [+] d = PoseManifold::Plus(x, E d),  E: 6 x k selection of the free axes,
//   Minus(y, x) = E^T PoseManifold::Minus(y, x); Jacobians PlusJacobian E and
// E^T MinusJacobian. At least one axis must be free (else: a constant block).
class PoseSubsetManifold final : public ceres::Manifold {
 public:
  explicit PoseSubsetManifold(const std::array<bool, 6>& free);
  int AmbientSize() const override { return 7; }
  int TangentSize() const override { return static_cast<int>(axes_.size()); }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;

 private:
  std::vector<int> axes_;  // the free tangent axes, ascending
};

// J_a = J_t MinusJacobian(x): the ambient (rows x 7) Jacobian of a pose block
// from its tangent (rows x 6) Jacobian, written row-major into `ambient`
// (Ceres' layout). x: the 7 pose parameters.
void PoseTangentToAmbientJacobian(const double* x,
                                  const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 6,
                                                                       Eigen::RowMajor>>& tangent,
                                  double* ambient);

}  // namespace rvlio

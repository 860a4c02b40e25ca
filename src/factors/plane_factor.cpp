#include "rvlio/factors/plane_factor.h"

#include <cmath>

#include "rvlio/common/check.h"
#include "rvlio/factors/parameter_blocks.h"

namespace rvlio {

PlaneFactor::PlaneFactor(const ConstraintList& constraints, const Pose3& T_imu_lidar,
                         double sigma_m) {
  RVLIO_CHECK_MSG(!constraints.empty(), "a plane factor needs at least one constraint");
  RVLIO_CHECK(sigma_m > 0.0);
  const int n = static_cast<int>(constraints.size());
  p_imu_.resize(3, n);
  u_.resize(3, n);
  u_dot_q_.resize(n);
  scale_.resize(n);
  for (int i = 0; i < n; ++i) {
    const Constraint& c = constraints[i];
    RVLIO_CHECK(c.weight >= 0.0);
    p_imu_.col(i) = T_imu_lidar * c.p_lidar;
    u_.col(i) = c.normal_world;
    u_dot_q_(i) = c.normal_world.dot(c.q_world);
    scale_(i) = std::sqrt(c.weight) / sigma_m;
  }
  set_num_residuals(n);
  mutable_parameter_block_sizes()->push_back(PoseBlock::kNumParams);
}

// Residuals for all points at once: r = s .* (colsum(U .* (R P)) + U^T t - u.q).
// Jacobian: the ambient row is the tangent row times MinusJacobian (manifolds.h):
//   [s (p_imu x R^T u)^T M_rot, s u^T], stored row-major (n x 7), i.e. as a
//   column-major 7 x n matrix.
bool PlaneFactor::Evaluate(double const* const* parameters, double* residuals,
                           double** jacobians) const {
  const PoseBlock pose = PoseBlock::FromArray(parameters[0]);
  const Eigen::Matrix3d R = pose.q_world_imu.normalized().toRotationMatrix();
  const Eigen::Vector3d& t = pose.p_world_imu;
  const int n = num_constraints();
  const Eigen::Matrix3Xd p_world = R * p_imu_;
  Eigen::Map<Eigen::VectorXd> r(residuals, n);
  r = scale_.cwiseProduct(u_.cwiseProduct(p_world).colwise().sum().transpose() +
                          u_.transpose() * t - u_dot_q_);
  if (jacobians == nullptr || jacobians[0] == nullptr) return true;

  const PoseBlock::MinusJacobianMatrix M = MinusJacobian(pose);
  const Eigen::Matrix<double, 4, 3> M_rot_T =
      M.block<3, 4>(PoseBlock::kRot, PoseBlock::kQuat).transpose();
  const Eigen::Matrix3Xd u_imu = R.transpose() * u_;
  Eigen::Matrix3Xd J_rot(3, n);
  for (int i = 0; i < n; ++i) J_rot.col(i) = scale_(i) * p_imu_.col(i).cross(u_imu.col(i));
  Eigen::Map<Eigen::Matrix<double, 7, Eigen::Dynamic>> J(jacobians[0], 7, n);
  J.topRows<4>().noalias() = M_rot_T * J_rot;
  J.bottomRows<3>() = u_ * scale_.asDiagonal();
  return true;
}

double CheckedPlaneInvSigma(const ConstraintList& constraints, double sigma_m) {
  RVLIO_CHECK_MSG(!constraints.empty(), "a plane factor needs at least one constraint");
  RVLIO_CHECK(sigma_m > 0.0);
  for (const Constraint& c : constraints) RVLIO_CHECK(c.weight >= 0.0);
  return 1.0 / sigma_m;
}

}  // namespace rvlio

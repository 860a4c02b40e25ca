#include "rvlio/smoother/plane_summary_factor.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "rvlio/common/check.h"
#include "rvlio/math/smoother_blocks.h"
#include "rvlio/math/so3.h"
#include "rvlio/smoother/manifolds.h"

namespace rvlio {
namespace {

constexpr double kRelativeEigenvalueFloor = 1e-15;

}  // namespace

// M = sum_i a_i a_i^T, then its square root through the eigendecomposition.
PlaneSummaryFactor::PlaneSummaryFactor(const ConstraintList& constraints,
                                       const Pose3& T_imu_lidar, double sigma_m,
                                       const Eigen::Vector3d& center_world)
    : center_(center_world), num_constraints_(static_cast<int>(constraints.size())) {
  RVLIO_CHECK(sigma_m > 0.0);
  M_.setZero();
  Vector13d a;
  for (const Constraint& c : constraints) {
    RVLIO_CHECK(c.weight >= 0.0);
    const double s = std::sqrt(c.weight) / sigma_m;
    const Eigen::Vector3d p_imu = T_imu_lidar * c.p_lidar;
    const Eigen::Vector3d& u = c.normal_world;
    for (int k = 0; k < 3; ++k) a.segment<3>(3 * k) = s * p_imu(k) * u;
    a.segment<3>(9) = s * u;
    a(12) = -s * u.dot(c.q_world - center_);
    // The full outer product in fixed size: each entry gets a_r a_c in the
    // same order as a lower-triangle rank update (and the product commutes,
    // so M_ is exactly symmetric), at a fraction of its cost.
    M_.noalias() += a * a.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Matrix13d> eig(M_);
  const double floor = kRelativeEigenvalueFloor * std::max(eig.eigenvalues().maxCoeff(), 0.0);
  const Vector13d sqrt_lambda =
      eig.eigenvalues().unaryExpr([floor](double l) { return l > floor ? std::sqrt(l) : 0.0; });
  sqrt_M_ = sqrt_lambda.asDiagonal() * eig.eigenvectors().transpose();
  set_num_residuals(13);
}

bool PlaneSummaryFactor::Evaluate(double const* const* parameters, double* residuals,
                                  double** jacobians) const {
  const PoseBlock pose = PoseBlock::FromArray(parameters[0]);
  const Eigen::Matrix3d R = pose.q_world_imu.normalized().toRotationMatrix();
  Vector13d z;
  z.head<9>() = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(R.data());  // column-major vec
  z.segment<3>(9) = pose.p_world_imu - center_;
  z(12) = 1.0;
  Eigen::Map<Vector13d> r(residuals);
  r.noalias() = sqrt_M_ * z;
  if (jacobians == nullptr || jacobians[0] == nullptr) return true;
  Eigen::Matrix<double, 13, 6> dz = Eigen::Matrix<double, 13, 6>::Zero();
  for (int k = 0; k < 3; ++k) {
    const Eigen::Matrix3d dR = R * so3::Hat(Eigen::Vector3d::Unit(k));
    dz.block<9, 1>(0, PoseBlock::kRot + k) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(dR.data());
  }
  dz.block<3, 3>(9, PoseBlock::kTrans).setIdentity();
  const Eigen::Matrix<double, 13, 6, Eigen::RowMajor> J_t = sqrt_M_ * dz;
  PoseTangentToAmbientJacobian(parameters[0], J_t, jacobians[0]);
  return true;
}

}  // namespace rvlio

#include "rvlio/factors/plane_summary_factor.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "rvlio/common/check.h"
#include "rvlio/factors/parameter_blocks.h"
#include "rvlio/math/so3.h"
#include "rvlio/factors/manifolds.h"

namespace rvlio {
namespace plane_summary {
namespace {

constexpr double kRelativeEigenvalueFloor = 1e-15;

}  // namespace

void AddRow(const Eigen::Vector3d& p, const Eigen::Vector3d& u, double d, double s, Matrix13d* M) {
  Vector13d a;
  for (int k = 0; k < 3; ++k) a.segment<3>(3 * k) = s * p(k) * u;
  a.segment<3>(9) = s * u;
  a(12) = -s * d;
  // The full outer product in fixed size: each entry gets a_r a_c in the
  // same order as a lower-triangle rank update (and the product commutes,
  // so M is exactly symmetric), at a fraction of its cost.
  M->noalias() += a * a.transpose();
}

// Through the eigendecomposition of the symmetric M.
Matrix13d SqrtInformation(const Matrix13d& M_lower) {
  const Matrix13d M = M_lower.selfadjointView<Eigen::Lower>();
  const Eigen::SelfAdjointEigenSolver<Matrix13d> eig(M);
  const double floor = kRelativeEigenvalueFloor * std::max(eig.eigenvalues().maxCoeff(), 0.0);
  const Vector13d sqrt_lambda =
      eig.eigenvalues().unaryExpr([floor](double l) { return l > floor ? std::sqrt(l) : 0.0; });
  return sqrt_lambda.asDiagonal() * eig.eigenvectors().transpose();
}

Eigen::Matrix<double, 9, 1> RightRotationColumn(const Eigen::Matrix3d& R, int k) {
  const Eigen::Matrix3d dR = R * so3::Hat(Eigen::Vector3d::Unit(k));
  return Eigen::Map<const Eigen::Matrix<double, 9, 1>>(dR.data());  // column-major vec
}

Vector13d PoseVector(const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                     const Eigen::Vector3d& center) {
  Vector13d z;
  z.head<9>() = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(R.data());  // column-major vec
  z.segment<3>(9) = t - center;
  z(12) = 1.0;
  return z;
}

Eigen::Matrix<double, 13, 6> PoseVectorJacobian(const Eigen::Matrix3d& R) {
  Eigen::Matrix<double, 13, 6> dz = Eigen::Matrix<double, 13, 6>::Zero();
  for (int k = 0; k < 3; ++k) dz.block<9, 1>(0, k) = RightRotationColumn(R, k);
  dz.block<3, 3>(9, 3).setIdentity();
  return dz;
}

}  // namespace plane_summary

// M = sum_i a_i a_i^T, then its square root.
PlaneSummaryFactor::PlaneSummaryFactor(const ConstraintList& constraints,
                                       const Pose3& T_imu_lidar, double sigma_m,
                                       const Eigen::Vector3d& center_world)
    : center_(center_world), num_constraints_(static_cast<int>(constraints.size())) {
  RVLIO_CHECK(sigma_m > 0.0);
  M_.setZero();
  for (const Constraint& c : constraints) {
    RVLIO_CHECK(c.weight >= 0.0);
    const Eigen::Vector3d& u = c.normal_world;
    plane_summary::AddRow(T_imu_lidar * c.p_lidar, u, u.dot(c.q_world - center_),
                          std::sqrt(c.weight) / sigma_m, &M_);
  }
  sqrt_M_ = plane_summary::SqrtInformation(M_);
  M_ = M_.selfadjointView<Eigen::Lower>();
  set_num_residuals(13);
}

bool PlaneSummaryFactor::Evaluate(double const* const* parameters, double* residuals,
                                  double** jacobians) const {
  const PoseBlock pose = PoseBlock::FromArray(parameters[0]);
  const Eigen::Matrix3d R = pose.q_world_imu.normalized().toRotationMatrix();
  const Vector13d z = plane_summary::PoseVector(R, pose.p_world_imu, center_);
  Eigen::Map<Vector13d> r(residuals);
  r.noalias() = sqrt_M_ * z;
  if (jacobians == nullptr || jacobians[0] == nullptr) return true;
  static_assert(PoseBlock::kRot == 0 && PoseBlock::kTrans == 3, "tangent order [d_rot, d_pos]");
  const Eigen::Matrix<double, 13, 6, Eigen::RowMajor> J_t =
      sqrt_M_ * plane_summary::PoseVectorJacobian(R);
  PoseTangentToAmbientJacobian(parameters[0], J_t, jacobians[0]);
  return true;
}

}  // namespace rvlio

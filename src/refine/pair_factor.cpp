#include "rvlio/refine/pair_factor.h"

#include <algorithm>
#include <cmath>

#include "rvlio/common/check.h"
#include "rvlio/factors/parameter_blocks.h"
#include "rvlio/math/so3.h"
#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/plane_summary_factor.h"

namespace rvlio {

using RowMajorX6 = Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>;

ScanPairPlaneFactor::ScanPairPlaneFactor(int constraints) {
  const size_t n = static_cast<size_t>(std::max(constraints, 0));
  p_imu_.reserve(n);
  u_j_.reserve(n);
  u_dot_q_.reserve(n);
  scale_.reserve(n);
}

void ScanPairPlaneFactor::Add(const Eigen::Vector3d& p_imu_k, const Eigen::Vector3d& u_j,
                              const Eigen::Vector3d& q_j, double weight, double sigma_m) {
  RVLIO_CHECK(weight >= 0.0 && sigma_m > 0.0);
  p_imu_.push_back(p_imu_k);
  u_j_.push_back(u_j);
  u_dot_q_.push_back(u_j.dot(q_j));
  scale_.push_back(std::sqrt(weight) / sigma_m);
}

void ScanPairPlaneFactor::Finalize() {
  RVLIO_CHECK_MSG(!scale_.empty(), "a pair plane factor needs at least one constraint");
  set_num_residuals(num_constraints());
  mutable_parameter_block_sizes()->assign({PoseBlock::kNumParams, PoseBlock::kNumParams});
}

bool ScanPairPlaneFactor::Evaluate(double const* const* parameters, double* residuals,
                                   double** jacobians) const {
  const PoseBlock pk = PoseBlock::FromArray(parameters[0]);
  const PoseBlock pj = PoseBlock::FromArray(parameters[1]);
  const Eigen::Matrix3d Rk = pk.q_world_imu.normalized().toRotationMatrix();
  const Eigen::Matrix3d Rj = pj.q_world_imu.normalized().toRotationMatrix();
  const Eigen::Matrix3d Rj_T_Rk = Rj.transpose() * Rk;
  const Eigen::Vector3d t_kj = Rj.transpose() * (pk.p_world_imu - pj.p_world_imu);
  const int n = num_constraints();
  const bool want_k = jacobians != nullptr && jacobians[0] != nullptr;
  const bool want_j = jacobians != nullptr && jacobians[1] != nullptr;
  RowMajorX6 Jk(want_k ? n : 0, 6), Jj(want_j ? n : 0, 6);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d x = Rj_T_Rk * p_imu_[i] + t_kj;
    const double s = scale_[i];
    residuals[i] = s * (u_j_[i].dot(x) - u_dot_q_[i]);
    if (!want_k && !want_j) continue;
    const Eigen::Vector3d u_w = Rj * u_j_[i];
    if (want_k) {
      Jk.row(i).head<3>() = s * p_imu_[i].cross(Rk.transpose() * u_w).transpose();
      Jk.row(i).tail<3>() = s * u_w.transpose();
    }
    if (want_j) {
      Jj.row(i).head<3>() = s * u_j_[i].cross(x).transpose();
      Jj.row(i).tail<3>() = -s * u_w.transpose();
    }
  }
  if (want_k) PoseTangentToAmbientJacobian(parameters[0], Jk, jacobians[0]);
  if (want_j) PoseTangentToAmbientJacobian(parameters[1], Jj, jacobians[1]);
  return true;
}

ScanPairSummaryFactor::ScanPairSummaryFactor() { m_.setZero(); }

void ScanPairSummaryFactor::Add(const Eigen::Vector3d& p_imu_k, const Eigen::Vector3d& u_j,
                                const Eigen::Vector3d& q_j, double weight, double sigma_m) {
  RVLIO_CHECK(!finalized_ && weight >= 0.0 && sigma_m > 0.0);
  plane_summary::AddRow(p_imu_k, u_j, u_j.dot(q_j), std::sqrt(weight) / sigma_m, &m_);
  ++num_constraints_;
}

void ScanPairSummaryFactor::Finalize() {
  RVLIO_CHECK_MSG(num_constraints_ > 0, "a pair summary factor needs at least one constraint");
  RVLIO_CHECK(!finalized_);
  m_ = plane_summary::SqrtInformation(m_);
  finalized_ = true;
}

bool ScanPairSummaryFactor::Evaluate(double const* const* parameters, double* residuals,
                                     double** jacobians) const {
  using Vector13d = plane_summary::Vector13d;
  const PoseBlock pk = PoseBlock::FromArray(parameters[0]);
  const PoseBlock pj = PoseBlock::FromArray(parameters[1]);
  const Eigen::Matrix3d Rk = pk.q_world_imu.normalized().toRotationMatrix();
  const Eigen::Matrix3d Rj = pj.q_world_imu.normalized().toRotationMatrix();
  const Eigen::Matrix3d R_jk = Rj.transpose() * Rk;
  const Eigen::Vector3d t_kj = Rj.transpose() * (pk.p_world_imu - pj.p_world_imu);
  Vector13d z;
  z.head<9>() = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(R_jk.data());
  z.segment<3>(9) = t_kj;
  z(12) = 1.0;
  Eigen::Map<Vector13d>(residuals).noalias() = m_ * z;
  if (jacobians == nullptr) return true;
  using Dz = Eigen::Matrix<double, 13, 6>;
  using J = Eigen::Matrix<double, 13, 6, Eigen::RowMajor>;
  if (jacobians[0] != nullptr) {
    Dz dz = Dz::Zero();
    for (int m = 0; m < 3; ++m)
      dz.block<9, 1>(0, PoseBlock::kRot + m) = plane_summary::RightRotationColumn(R_jk, m);
    dz.block<3, 3>(9, PoseBlock::kTrans) = Rj.transpose();
    const J J_t = m_ * dz;
    PoseTangentToAmbientJacobian(parameters[0], J_t, jacobians[0]);
  }
  if (jacobians[1] != nullptr) {
    Dz dz = Dz::Zero();
    for (int m = 0; m < 3; ++m) {
      const Eigen::Matrix3d hat = so3::Hat(Eigen::Vector3d::Unit(m));
      const Eigen::Matrix3d dR = -hat * R_jk;
      dz.block<9, 1>(0, PoseBlock::kRot + m) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(dR.data());
      dz.block<3, 1>(9, PoseBlock::kRot + m) = -hat * t_kj;
    }
    dz.block<3, 3>(9, PoseBlock::kTrans) = -Rj.transpose();
    const J J_t = m_ * dz;
    PoseTangentToAmbientJacobian(parameters[1], J_t, jacobians[1]);
  }
  return true;
}

}  // namespace rvlio

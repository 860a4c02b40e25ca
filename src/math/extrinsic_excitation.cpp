#include "rvlio/math/extrinsic_excitation.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "rvlio/common/check.h"
#include "rvlio/math/so3.h"

namespace rvlio {

ExtrinsicExcitation::ExtrinsicExcitation(const Vector6d& prior_std) : prior_std_(prior_std) {
  RVLIO_CHECK(prior_std.minCoeff() > 0.0);
}

void ExtrinsicExcitation::Observe(const Matrix6d& covariance) {
  for (int i = 0; i < 6; ++i) {
    const double variance = covariance(i, i);
    if (!std::isfinite(variance)) continue;
    std_ratio_(i) = std::sqrt(std::max(variance, 0.0)) / prior_std_(i);
  }
  Latch();
}

void ExtrinsicExcitation::Latch() {
  for (int i = 0; i < 6; ++i)
    if (rotation_ok_[i] && std_ratio_(i) < kExcitedStdRatio) excited_[i] = true;
}

namespace {

// Diagonal of the pseudo-inverse of a symmetric PSD 3x3 (infinite where the
// axis has a component in the null space).
Eigen::Vector3d PseudoInverseDiagonal(const Eigen::Matrix3d& W) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(W);
  const double floor = 1e-9 * std::max(eig.eigenvalues().maxCoeff(), 1e-12);
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d v = eig.eigenvectors().col(k);
    const double l = eig.eigenvalues()(k);
    for (int i = 0; i < 3; ++i) {
      if (std::abs(v(i)) < 1e-6) continue;
      d(i) += l > floor ? v(i) * v(i) / l : std::numeric_limits<double>::infinity();
    }
  }
  return d;
}

}  // namespace

void ExtrinsicExcitation::CountScan(TimeNs t_ns, const Eigen::Matrix3d& R_world_imu,
                                    const Eigen::Matrix3d& R_imu_lidar) {
  attitudes_.push_back({t_ns, R_world_imu});
  while (attitudes_.size() >= 2 && attitudes_[1].t_ns <= t_ns - kRotationBaselineNs)
    attitudes_.pop_front();
  if (attitudes_.front().t_ns <= t_ns - kRotationBaselineNs) {
    const Eigen::Matrix3d phi_x = so3::Hat(so3::Log(attitudes_.front().R_world_imu.transpose() * R_world_imu));
    W_ += phi_x.transpose() * phi_x;
  }
  const double max_variance = 1.0 / kMinRotationInfo;
  const Eigen::Vector3d pos = PseudoInverseDiagonal(W_);
  const Eigen::Vector3d rot = PseudoInverseDiagonal(R_imu_lidar.transpose() * W_ * R_imu_lidar);
  for (int i = 0; i < 3; ++i) {
    rotation_ok_[i] = rotation_ok_[i] || rot(i) <= max_variance;
    rotation_ok_[3 + i] = rotation_ok_[3 + i] || pos(i) <= max_variance;
  }
  Latch();
  ++scans_;
  free_axis_scans_ += std::count(excited_.begin(), excited_.end(), true);
}

bool ExtrinsicExcitation::any_excited() const {
  return std::find(excited_.begin(), excited_.end(), true) != excited_.end();
}

double ExtrinsicExcitation::excited_fraction() const {
  return scans_ > 0 ? static_cast<double>(free_axis_scans_) / (6.0 * static_cast<double>(scans_))
                    : 0.0;
}

}  // namespace rvlio

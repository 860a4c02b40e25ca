#pragma once
// Excitation monitor of an online-estimated LiDAR-IMU extrinsic T_imu_lidar
// (tangent [dphi (3, rad, right perturbation of R_imu_lidar), dt (3, m)]),
// shared by the IESKF and the smoother backends.
//
// An axis of the extrinsic counts as excited once the marginal standard
// deviation the measurements leave on it (posterior covariance of the
// extrinsic block, computed as if all six axes were estimated) has fallen
// below kExcitedStdRatio times its prior standard deviation, i.e. the motion
// brought at least (1 / ratio^2 - 1) = 3 times the prior's information on it.
// Until then the backend keeps that axis frozen at its prior value; an axis
// once excited stays free (the posterior does not widen without process
// noise, and latching avoids toggling around the threshold).
#include <array>

#include <Eigen/Core>

#include "rvlio/math/pose.h"

namespace rvlio {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

class ExtrinsicExcitation {
 public:
  static constexpr double kExcitedStdRatio = 0.5;

  ExtrinsicExcitation() = default;
  // prior_std: [rot (rad) x3, pos (m) x3], all > 0.
  explicit ExtrinsicExcitation(const Vector6d& prior_std);

  // The current posterior covariance of the extrinsic block (tangent order
  // above): updates the std ratios and latches newly excited axes.
  void Observe(const Matrix6d& covariance);
  // One processed scan: accumulates the excited fraction.
  void CountScan();

  bool excited(int axis) const { return excited_[axis]; }
  bool any_excited() const;
  // Fraction of (scan, axis) pairs in which the axis was free, over the scans counted.
  double excited_fraction() const;
  const Vector6d& std_ratio() const { return std_ratio_; }  // posterior / prior std
  const Vector6d& prior_std() const { return prior_std_; }

 private:
  Vector6d prior_std_ = Vector6d::Ones();
  Vector6d std_ratio_ = Vector6d::Ones();
  std::array<bool, 6> excited_ = {false, false, false, false, false, false};
  long long scans_ = 0;
  long long free_axis_scans_ = 0;
};

}  // namespace rvlio

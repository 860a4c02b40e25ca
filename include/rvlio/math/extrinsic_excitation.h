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
// The backends treat their map as exact, which lends the covariance
// information the motion cannot give (the map's own frame is made with the
// configured extrinsic: a static sensor would look calibrated). So an axis
// also needs rotational excitation (the hand-eye condition): with
// phi_k = Log(R_world_imu(t_k - 1 s)^T R_world_imu(t_k)) the IMU's rotation
// over the last second at each scan k, W = sum_k Hat(phi_k)^T Hat(phi_k)
// (rad^2) is the information rotations bring on a rotation or translation
// offset (rotation about a only reveals offsets orthogonal to a); translation
// axis i (IMU frame) is excited by rotation when (W^+)_ii <= 1 / kMinRotationInfo,
// rotation axis i (LiDAR frame) likewise with R_imu_lidar^T W R_imu_lidar.
// Until both hold the backend keeps that axis frozen at its prior value; an
// axis once excited stays free (latched: no toggling around the thresholds).
#include <array>
#include <deque>

#include <Eigen/Core>

#include "rvlio/common/time.h"
#include "rvlio/math/pose.h"

namespace rvlio {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

class ExtrinsicExcitation {
 public:
  static constexpr double kExcitedStdRatio = 0.5;
  static constexpr double kMinRotationInfo = 0.5;      // rad^2, see above
  static constexpr TimeNs kRotationBaselineNs = 1000000000;  // 1 s

  ExtrinsicExcitation() = default;
  // prior_std: [rot (rad) x3, pos (m) x3], all > 0.
  explicit ExtrinsicExcitation(const Vector6d& prior_std);

  // The current posterior covariance of the extrinsic block (tangent order
  // above): updates the std ratios and latches newly excited axes.
  void Observe(const Matrix6d& covariance);
  // One processed scan at t_ns with the IMU attitude and the current
  // extrinsic rotation: accumulates W and the excited fraction.
  void CountScan(TimeNs t_ns, const Eigen::Matrix3d& R_world_imu, const Eigen::Matrix3d& R_imu_lidar);

  bool excited(int axis) const { return excited_[axis]; }
  bool any_excited() const;
  // Fraction of (scan, axis) pairs in which the axis was free, over the scans counted.
  double excited_fraction() const;
  const Vector6d& std_ratio() const { return std_ratio_; }  // posterior / prior std
  const Vector6d& prior_std() const { return prior_std_; }
  const Eigen::Matrix3d& rotation_information() const { return W_; }  // W, IMU frame

 private:
  void Latch();

  struct Attitude {
    TimeNs t_ns;
    Eigen::Matrix3d R_world_imu;
  };
  Vector6d prior_std_ = Vector6d::Ones();
  Vector6d std_ratio_ = Vector6d::Ones();
  std::array<bool, 6> excited_ = {false, false, false, false, false, false};
  std::array<bool, 6> rotation_ok_ = {false, false, false, false, false, false};
  Eigen::Matrix3d W_ = Eigen::Matrix3d::Zero();
  std::deque<Attitude> attitudes_;  // the last kRotationBaselineNs and one older
  long long scans_ = 0;
  long long free_axis_scans_ = 0;
};

}  // namespace rvlio

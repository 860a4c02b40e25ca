#pragma once
// The point-to-plane residual of a scan whose LiDAR clock is off by an
// estimated time offset (lidar.estimate_time_offset), shared by the IESKF
// (augmented state) and the smoother (one window parameter).
#include <Eigen/Core>

#include "rvlio/constraints/constraint.h"
#include "rvlio/math/pose.h"
#include "rvlio/imu/filter_state.h"

namespace rvlio {

// Online LiDAR-IMU time offset (lidar.estimate_time_offset): the scan is
// taken dt = td - td_lin after the state's time, where td_lin is the offset
// the prediction and deskew used. Its pose is the state's IMU pose carried
// over dt by the motion held at the state's time (AdvanceImuPose): to first
// order the rotation moves by w dt and the position by v dt.
struct ScanTimeMotion {
  Eigen::Vector3d gyro_imu = Eigen::Vector3d::Zero();   // rad/s, bias removed
  Eigen::Vector3d acc_world = Eigen::Vector3d::Zero();  // m/s^2, gravity included
};

// The IMU pose at the scan's time: x's pose advanced by dt_s along `motion`.
Pose3 ScanTimePose(const FilterState& x, const ScanTimeMotion& motion, double dt_s);

// Jacobian columns of a residual with the time offset estimated:
// [dtheta, dp, dphi, dt_ext, dv, d(td)] (FilterState perturbations of x, and
// the offset in seconds).
using TimeOffsetJacobian = Eigen::Matrix<double, 1, 16>;

// What every constraint of a scan shares at one linearization point (x,
// motion, dt): the scan-time IMU pose and the chain from the 12 columns h of
// PointToPlaneResidualWithExtrinsics at that pose ([dtheta, dp, dphi, dt_ext]
// at the scan's time) to TimeOffsetJacobian's 16: J = h * h_to_J. Computed
// once per linearization point, so the per-constraint work is that of the
// residual without the offset; a sum of h^T h over the constraints maps to
// the 16 columns as h_to_J^T (sum h^T h) h_to_J.
struct ScanTimeLinearization {
  Pose3 T_world_imu;
  Eigen::Matrix<double, 12, 16> h_to_J;
};

ScanTimeLinearization LinearizeAtScanTime(const FilterState& x, const ScanTimeMotion& motion,
                                          double dt_s);

// r of Eq. (3) at lin.T_world_imu; J (optional) = dr / the columns above
// (the pose and velocity columns perturb x at its own time).
double PointToPlaneResidualWithTimeOffset(const Constraint& c, const ScanTimeLinearization& lin,
                                          const Pose3& T_imu_lidar,
                                          TimeOffsetJacobian* J = nullptr);

// The same for one constraint, linearized on the spot.
double PointToPlaneResidualWithTimeOffset(const Constraint& c, const FilterState& x,
                                          const ScanTimeMotion& motion, double dt_s,
                                          TimeOffsetJacobian* J = nullptr);

}  // namespace rvlio

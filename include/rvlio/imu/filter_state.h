#pragma once
// The filter state of the paper (Section 2) and its manifold
//   M = SO(3) x R^12 x SO(3) x R^6   (24-dim tangent space)
//   x = [R_world_imu, p_world_imu, v_world_imu, b_g, b_a, R_imu_lidar, t_imu_lidar, g_world].
// The paper writes R^6 for (t_imu_lidar, g); gravity is kept Euclidean (R^3)
// here, so the error state is 24-dim with the offsets below.
//
// Boxplus / boxminus (paper Eq. 1, 2) use right perturbations on both
// rotations and plain addition elsewhere:
//   x [+] d : R_world_imu Exp(d_rot), p + d_pos, ..., R_imu_lidar Exp(d_ext_rot), ...
//   y [-] x : Log(x.R^T y.R), y.p - x.p, ...
#include <Eigen/Core>

#include "rvlio/math/pose.h"

namespace rvlio {

using Vector24d = Eigen::Matrix<double, 24, 1>;
using Matrix24d = Eigen::Matrix<double, 24, 24>;

struct FilterState {
  // Tangent-space offsets of each component (3 entries each).
  static constexpr int kRot = 0;      // R_world_imu, right perturbation (rad)
  static constexpr int kPos = 3;      // p_world_imu (m)
  static constexpr int kVel = 6;      // v_world_imu (m/s)
  static constexpr int kBg = 9;       // gyroscope bias (rad/s)
  static constexpr int kBa = 12;      // accelerometer bias (m/s^2)
  static constexpr int kExtRot = 15;  // R_imu_lidar, right perturbation (rad)
  static constexpr int kExtPos = 18;  // t_imu_lidar (m)
  static constexpr int kGrav = 21;    // g_world (m/s^2)
  static constexpr int kDim = 24;

  Eigen::Matrix3d R_world_imu = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_world_imu = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_world_imu = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();  // gyro bias, IMU frame
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();  // accel bias, IMU frame
  Eigen::Matrix3d R_imu_lidar = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_imu_lidar = Eigen::Vector3d::Zero();
  // Gravity as a vector in the world frame (z up: (0, 0, -|g|)).
  Eigen::Vector3d g_world = Eigen::Vector3d(0.0, 0.0, -9.81);

  Pose3 T_world_imu() const { return Pose3(R_world_imu, p_world_imu); }
  Pose3 T_imu_lidar() const { return Pose3(R_imu_lidar, t_imu_lidar); }
  Pose3 T_world_lidar() const { return T_world_imu() * T_imu_lidar(); }
};

// x [+] delta (see the header comment).
FilterState Boxplus(const FilterState& x, const Vector24d& delta);

// y [-] x, such that Boxplus(x, Boxminus(y, x)) == y and, for rotation parts
// of delta shorter than pi, Boxminus(Boxplus(x, delta), x) == delta.
Vector24d Boxminus(const FilterState& y, const FilterState& x);

// J = d((x [+] d) [-] x0) / d d at d = 0, the paper's J^v of Eq. (2): the
// identity except JrInv(Log(x0.R^T x.R)) on the two rotation blocks.
Matrix24d BoxminusJacobian(const FilterState& x, const FilterState& x0);

// J^{-1} of the above (Jr on the rotation blocks), as used in Eq. (1).
Matrix24d BoxminusJacobianInverse(const FilterState& x, const FilterState& x0);

}  // namespace rvlio

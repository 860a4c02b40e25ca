#pragma once
// Parameter blocks of the sliding-window smoother, as plain structs with
// their manifold operations. The raw-array forms (double*) are what Ceres
// cost functions and a ceres::Manifold wrapper use; this header does not
// include Ceres.
//
// PoseBlock: 7 parameters [qx qy qz qw px py pz] (q_world_imu in Eigen's
//   memory order, then p_world_imu), 6-dof tangent [d_rot, d_pos]:
//     x [+] d = (q Exp(d_rot), p + d_pos)       right perturbation on rotation,
//     y [-] x = (Log(q_x^-1 q_y), p_y - p_x)    position in the world frame,
//   the same convention as FilterState (imu/filter_state.h).
// SpeedBiasBlock: 9 parameters [v_world_imu, b_g, b_a], Euclidean.
// All matrices exposed as double* are row-major (Ceres' convention).
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rvlio/math/pose.h"

namespace rvlio {

struct PoseBlock {
  static constexpr int kNumParams = 7;
  static constexpr int kTangentDim = 6;
  static constexpr int kQuat = 0;   // parameter offset of [qx qy qz qw]
  static constexpr int kPos = 4;    // parameter offset of [px py pz]
  static constexpr int kRot = 0;    // tangent offset of d_rot
  static constexpr int kTrans = 3;  // tangent offset of d_pos
  using Tangent = Eigen::Matrix<double, 6, 1>;
  using PlusJacobianMatrix = Eigen::Matrix<double, 7, 6, Eigen::RowMajor>;
  using MinusJacobianMatrix = Eigen::Matrix<double, 6, 7, Eigen::RowMajor>;

  Eigen::Quaterniond q_world_imu = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_world_imu = Eigen::Vector3d::Zero();

  PoseBlock() = default;
  PoseBlock(const Eigen::Quaterniond& q, const Eigen::Vector3d& p);
  explicit PoseBlock(const Pose3& T_world_imu);

  Pose3 ToPose3() const { return Pose3(q_world_imu, p_world_imu); }
  void ToArray(double* params) const;                // writes 7 doubles
  static PoseBlock FromArray(const double* params);  // reads 7 doubles

  // Raw-array forms of Plus / Minus / their Jacobians (for ceres::Manifold).
  static void Plus(const double* x, const double* delta, double* x_plus_delta);
  static void Minus(const double* y, const double* x, double* y_minus_x);
  static void PlusJacobian(const double* x, double* jacobian_7x6);
  static void MinusJacobian(const double* x, double* jacobian_6x7);
};

struct SpeedBiasBlock {
  static constexpr int kNumParams = 9;
  static constexpr int kTangentDim = 9;
  static constexpr int kVel = 0;  // m/s, world frame
  static constexpr int kBg = 3;   // rad/s, IMU frame
  static constexpr int kBa = 6;   // m/s^2, IMU frame
  using Tangent = Eigen::Matrix<double, 9, 1>;

  Eigen::Vector3d v_world_imu = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();

  void ToArray(double* params) const;                     // writes 9 doubles
  static SpeedBiasBlock FromArray(const double* params);  // reads 9 doubles
};

// x [+] delta; the quaternion of the result is normalized.
PoseBlock Plus(const PoseBlock& x, const PoseBlock::Tangent& delta);
// y [-] x, |rotation part| <= pi; Plus(x, Minus(y, x)) == y.
PoseBlock::Tangent Minus(const PoseBlock& y, const PoseBlock& x);
// d Plus(x, d) / d d at d = 0 (7x6), with respect to the 7 parameters.
PoseBlock::PlusJacobianMatrix PlusJacobian(const PoseBlock& x);
// d Minus(y, x) / d y at y = x (6x7); MinusJacobian(x) * PlusJacobian(x) = I.
PoseBlock::MinusJacobianMatrix MinusJacobian(const PoseBlock& x);

SpeedBiasBlock Plus(const SpeedBiasBlock& x, const SpeedBiasBlock::Tangent& delta);
SpeedBiasBlock::Tangent Minus(const SpeedBiasBlock& y, const SpeedBiasBlock& x);

}  // namespace rvlio

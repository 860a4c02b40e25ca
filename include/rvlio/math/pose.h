#pragma once
// A rigid transform T_a_b: maps coordinates in frame b to frame a,
// p_a = R_a_b p_b + t_a_b.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rvlio {

struct Pose3 {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Pose3() = default;
  Pose3(const Eigen::Matrix3d& R_in, const Eigen::Vector3d& t_in) : R(R_in), t(t_in) {}
  Pose3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t_in)
      : R(q.normalized().toRotationMatrix()), t(t_in) {}

  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return R * p + t; }
  Pose3 operator*(const Pose3& o) const { return Pose3(R * o.R, R * o.t + t); }
  Pose3 Inverse() const { return Pose3(R.transpose(), -(R.transpose() * t)); }
  Eigen::Quaterniond quaternion() const { return Eigen::Quaterniond(R).normalized(); }
};

}  // namespace rvlio

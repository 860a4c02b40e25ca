#pragma once
// SO(3) toolbox: hat/vee, exponential and logarithm maps (matrix and unit
// quaternion forms), and the right/left Jacobians of the exponential map.
//
// Conventions (used by every module):
// - A rotation vector w = theta * axis, theta = |w| in radians.
// - Right perturbation: R (+) d = R Exp(d). The paper's boxplus on SO(3).
// - Jr(w) is the right Jacobian:  Exp(w + d) ~= Exp(w) Exp(Jr(w) d),
//                                 Log(Exp(w) Exp(d)) ~= w + JrInv(w) d.
//   Jl(w) is the left Jacobian:   Exp(w + d) ~= Exp(Jl(w) d) Exp(w),
//                                 Log(Exp(d) Exp(w)) ~= w + JlInv(w) d.
//   Jl(w) = Jr(-w) = Jr(w)^T.
// - Log returns a rotation vector with |w| <= pi. At exactly pi the sign of
//   the axis is arbitrary (both are the same rotation).
// - Quaternions are Eigen's (Hamilton, memory order x y z w).
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rvlio {
namespace so3 {

// Skew-symmetric matrix: Hat(w) v = w x v.
inline Eigen::Matrix3d Hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d W;
  // clang-format off
  W << 0.0, -w.z(), w.y(),
       w.z(), 0.0, -w.x(),
       -w.y(), w.x(), 0.0;
  // clang-format on
  return W;
}

// Inverse of Hat; reads the antisymmetric part of W (W need not be exactly
// skew: Vee(W) = Vee((W - W^T) / 2)).
inline Eigen::Vector3d Vee(const Eigen::Matrix3d& W) {
  return 0.5 * Eigen::Vector3d(W(2, 1) - W(1, 2), W(0, 2) - W(2, 0), W(1, 0) - W(0, 1));
}

// Rodrigues' formula, with a Taylor expansion for small angles.
Eigen::Matrix3d Exp(const Eigen::Vector3d& w);

// Rotation vector of R, |result| <= pi. Robust near 0 and near pi (goes
// through a quaternion computed from the largest diagonal element).
Eigen::Vector3d Log(const Eigen::Matrix3d& R);

// Unit quaternion exp/log, consistent with Exp/Log above:
// ExpQuat(w).toRotationMatrix() == Exp(w), LogQuat(q) == Log(q.toRotationMatrix()).
// LogQuat accepts non-unit quaternions (it depends only on the direction of q)
// and treats q and -q as the same rotation.
Eigen::Quaterniond ExpQuat(const Eigen::Vector3d& w);
Eigen::Vector3d LogQuat(const Eigen::Quaterniond& q);

// Right and left Jacobians of Exp and their inverses (see the header comment).
// JrInv and JlInv are singular at |w| = 2 pi; they are well defined at pi.
Eigen::Matrix3d Jr(const Eigen::Vector3d& w);
Eigen::Matrix3d JrInv(const Eigen::Vector3d& w);
Eigen::Matrix3d Jl(const Eigen::Vector3d& w);
Eigen::Matrix3d JlInv(const Eigen::Vector3d& w);

// d Log(R Exp(d)) / d d at d = 0, i.e. JrInv(Log(R)).
Eigen::Matrix3d LogRightJacobian(const Eigen::Matrix3d& R);

// d (Exp(w) v) / d w = -Exp(w) Hat(v) Jr(w).
Eigen::Matrix3d ExpTimesVectorJacobian(const Eigen::Vector3d& w, const Eigen::Vector3d& v);

}  // namespace so3

// Roll, pitch, yaw (deg) of R = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Vector3d RpyDeg(const Eigen::Matrix3d& R);

}  // namespace rvlio

#include "rvlio/factors/parameter_blocks.h"

#include "rvlio/math/so3.h"

namespace rvlio {

PoseBlock::PoseBlock(const Eigen::Quaterniond& q, const Eigen::Vector3d& p)
    : q_world_imu(q), p_world_imu(p) {}

PoseBlock::PoseBlock(const Pose3& T_world_imu)
    : q_world_imu(T_world_imu.quaternion()), p_world_imu(T_world_imu.t) {}

void PoseBlock::ToArray(double* params) const {
  Eigen::Map<Eigen::Quaterniond> q(params + kQuat);
  Eigen::Map<Eigen::Vector3d> p(params + kPos);
  q = q_world_imu;
  p = p_world_imu;
}

PoseBlock PoseBlock::FromArray(const double* params) {
  return PoseBlock(Eigen::Map<const Eigen::Quaterniond>(params + kQuat),
                   Eigen::Map<const Eigen::Vector3d>(params + kPos));
}

void PoseBlock::Plus(const double* x, const double* delta, double* x_plus_delta) {
  const Tangent d = Eigen::Map<const Tangent>(delta);
  rvlio::Plus(FromArray(x), d).ToArray(x_plus_delta);
}

void PoseBlock::Minus(const double* y, const double* x, double* y_minus_x) {
  Eigen::Map<Tangent> out(y_minus_x);
  out = rvlio::Minus(FromArray(y), FromArray(x));
}

void PoseBlock::PlusJacobian(const double* x, double* jacobian_7x6) {
  Eigen::Map<PlusJacobianMatrix> J(jacobian_7x6);
  J = rvlio::PlusJacobian(FromArray(x));
}

void PoseBlock::MinusJacobian(const double* x, double* jacobian_6x7) {
  Eigen::Map<MinusJacobianMatrix> J(jacobian_6x7);
  J = rvlio::MinusJacobian(FromArray(x));
}

void SpeedBiasBlock::ToArray(double* params) const {
  Eigen::Map<Tangent> out(params);
  out << v_world_imu, bg, ba;
}

SpeedBiasBlock SpeedBiasBlock::FromArray(const double* params) {
  SpeedBiasBlock b;
  b.v_world_imu = Eigen::Map<const Eigen::Vector3d>(params + kVel);
  b.bg = Eigen::Map<const Eigen::Vector3d>(params + kBg);
  b.ba = Eigen::Map<const Eigen::Vector3d>(params + kBa);
  return b;
}

PoseBlock Plus(const PoseBlock& x, const PoseBlock::Tangent& delta) {
  const Eigen::Quaterniond q = x.q_world_imu * so3::ExpQuat(delta.segment<3>(PoseBlock::kRot));
  return PoseBlock(q.normalized(), x.p_world_imu + delta.segment<3>(PoseBlock::kTrans));
}

PoseBlock::Tangent Minus(const PoseBlock& y, const PoseBlock& x) {
  PoseBlock::Tangent d;
  d.segment<3>(PoseBlock::kRot) = so3::LogQuat(x.q_world_imu.conjugate() * y.q_world_imu);
  d.segment<3>(PoseBlock::kTrans) = y.p_world_imu - x.p_world_imu;
  return d;
}

// q Exp(d) ~= q (x) [d/2, 1]; with q = [qv, qw] the Hamilton product gives
//   vec = qw d/2 + qv x d/2,  w = qw - qv . d/2
// so d vec/d d = (qw I + Hat(qv)) / 2 and d w/d d = -qv^T / 2.
PoseBlock::PlusJacobianMatrix PlusJacobian(const PoseBlock& x) {
  const Eigen::Vector3d qv = x.q_world_imu.vec();
  const double qw = x.q_world_imu.w();
  PoseBlock::PlusJacobianMatrix J = PoseBlock::PlusJacobianMatrix::Zero();
  J.block<3, 3>(PoseBlock::kQuat, PoseBlock::kRot) =
      0.5 * (qw * Eigen::Matrix3d::Identity() + so3::Hat(qv));
  J.block<1, 3>(PoseBlock::kQuat + 3, PoseBlock::kRot) = -0.5 * qv.transpose();
  J.block<3, 3>(PoseBlock::kPos, PoseBlock::kTrans) = Eigen::Matrix3d::Identity();
  return J;
}

// Log(q^-1 y) ~= 2 vec(q^-1 (x) y) near y = q, and
//   vec(q^-1 (x) y) = qw yv - yw qv - qv x yv,
// so d/d yv = 2 (qw I - Hat(qv)) and d/d yw = -2 qv.
PoseBlock::MinusJacobianMatrix MinusJacobian(const PoseBlock& x) {
  const Eigen::Vector3d qv = x.q_world_imu.vec();
  const double qw = x.q_world_imu.w();
  PoseBlock::MinusJacobianMatrix J = PoseBlock::MinusJacobianMatrix::Zero();
  J.block<3, 3>(PoseBlock::kRot, PoseBlock::kQuat) =
      2.0 * (qw * Eigen::Matrix3d::Identity() - so3::Hat(qv));
  J.block<3, 1>(PoseBlock::kRot, PoseBlock::kQuat + 3) = -2.0 * qv;
  J.block<3, 3>(PoseBlock::kTrans, PoseBlock::kPos) = Eigen::Matrix3d::Identity();
  return J;
}

SpeedBiasBlock Plus(const SpeedBiasBlock& x, const SpeedBiasBlock::Tangent& delta) {
  SpeedBiasBlock y;
  y.v_world_imu = x.v_world_imu + delta.segment<3>(SpeedBiasBlock::kVel);
  y.bg = x.bg + delta.segment<3>(SpeedBiasBlock::kBg);
  y.ba = x.ba + delta.segment<3>(SpeedBiasBlock::kBa);
  return y;
}

SpeedBiasBlock::Tangent Minus(const SpeedBiasBlock& y, const SpeedBiasBlock& x) {
  SpeedBiasBlock::Tangent d;
  d.segment<3>(SpeedBiasBlock::kVel) = y.v_world_imu - x.v_world_imu;
  d.segment<3>(SpeedBiasBlock::kBg) = y.bg - x.bg;
  d.segment<3>(SpeedBiasBlock::kBa) = y.ba - x.ba;
  return d;
}

}  // namespace rvlio

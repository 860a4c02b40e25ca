#include "rvlio/imu/filter_state.h"

#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

using S = FilterState;

// Builds the identity with f(Log(x0.R^T x.R)) on both rotation blocks.
template <typename BlockFn>
Matrix24d RotationBlockDiagonal(const FilterState& x, const FilterState& x0, BlockFn f) {
  Matrix24d J = Matrix24d::Identity();
  J.block<3, 3>(S::kRot, S::kRot) = f(so3::Log(x0.R_world_imu.transpose() * x.R_world_imu));
  J.block<3, 3>(S::kExtRot, S::kExtRot) = f(so3::Log(x0.R_imu_lidar.transpose() * x.R_imu_lidar));
  return J;
}

}  // namespace

FilterState Boxplus(const FilterState& x, const Vector24d& delta) {
  FilterState y;
  y.R_world_imu = x.R_world_imu * so3::Exp(delta.segment<3>(S::kRot));
  y.p_world_imu = x.p_world_imu + delta.segment<3>(S::kPos);
  y.v_world_imu = x.v_world_imu + delta.segment<3>(S::kVel);
  y.bg = x.bg + delta.segment<3>(S::kBg);
  y.ba = x.ba + delta.segment<3>(S::kBa);
  y.R_imu_lidar = x.R_imu_lidar * so3::Exp(delta.segment<3>(S::kExtRot));
  y.t_imu_lidar = x.t_imu_lidar + delta.segment<3>(S::kExtPos);
  y.g_world = x.g_world + delta.segment<3>(S::kGrav);
  return y;
}

Vector24d Boxminus(const FilterState& y, const FilterState& x) {
  Vector24d d;
  d.segment<3>(S::kRot) = so3::Log(x.R_world_imu.transpose() * y.R_world_imu);
  d.segment<3>(S::kPos) = y.p_world_imu - x.p_world_imu;
  d.segment<3>(S::kVel) = y.v_world_imu - x.v_world_imu;
  d.segment<3>(S::kBg) = y.bg - x.bg;
  d.segment<3>(S::kBa) = y.ba - x.ba;
  d.segment<3>(S::kExtRot) = so3::Log(x.R_imu_lidar.transpose() * y.R_imu_lidar);
  d.segment<3>(S::kExtPos) = y.t_imu_lidar - x.t_imu_lidar;
  d.segment<3>(S::kGrav) = y.g_world - x.g_world;
  return d;
}

// (x [+] d) [-] x0 on a rotation block is Log(R0^T R Exp(d)) ~= phi + JrInv(phi) d
// with phi = Log(R0^T R); every Euclidean block has derivative I.
Matrix24d BoxminusJacobian(const FilterState& x, const FilterState& x0) {
  return RotationBlockDiagonal(x, x0, [](const Eigen::Vector3d& phi) { return so3::JrInv(phi); });
}

Matrix24d BoxminusJacobianInverse(const FilterState& x, const FilterState& x0) {
  return RotationBlockDiagonal(x, x0, [](const Eigen::Vector3d& phi) { return so3::Jr(phi); });
}

}  // namespace rvlio

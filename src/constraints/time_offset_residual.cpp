#include "rvlio/constraints/time_offset_residual.h"

#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/imu/pose_history.h"
#include "rvlio/math/so3.h"

namespace rvlio {

Pose3 ScanTimePose(const FilterState& x, const ScanTimeMotion& motion, double dt_s) {
  ImuPoseSample s;
  s.R_world_imu = x.R_world_imu;
  s.p_world_imu = x.p_world_imu;
  s.v_world_imu = x.v_world_imu;
  s.gyro_imu = motion.gyro_imu;
  s.acc_world = motion.acc_world;
  return AdvanceImuPose(s, dt_s);
}

// With T = ScanTimePose = (R Exp(w dt), p + v dt + a dt^2 / 2) and h the
// Jacobian at T (point_to_plane.h):
//   R Exp(dtheta) Exp(w dt) = R Exp(w dt) Exp(Exp(-w dt) dtheta)
//     => dr/dtheta = h_theta Exp(w dt)^T;  dr/dp = h_p;  dr/dv = h_p dt;
//   R Exp(w (dt + e)) = R Exp(w dt) Exp(w e)
//     => dr/d(td) = h_theta w + h_p (v + a dt);
// the extrinsic columns pass through.
ScanTimeLinearization LinearizeAtScanTime(const FilterState& x, const ScanTimeMotion& motion,
                                          double dt_s) {
  ScanTimeLinearization lin;
  lin.T_world_imu = ScanTimePose(x, motion, dt_s);
  Eigen::Matrix<double, 12, 16>& M = lin.h_to_J;
  M.setZero();
  M.block<3, 3>(0, 0) = so3::Exp(motion.gyro_imu * dt_s).transpose();
  M.block<9, 9>(3, 3).setIdentity();
  M.block<3, 3>(3, 12) = Eigen::Matrix3d::Identity() * dt_s;
  M.block<3, 1>(0, 15) = motion.gyro_imu;
  M.block<3, 1>(3, 15) = x.v_world_imu + motion.acc_world * dt_s;
  return lin;
}

double PointToPlaneResidualWithTimeOffset(const Constraint& c, const ScanTimeLinearization& lin,
                                          const Pose3& T_imu_lidar, TimeOffsetJacobian* J) {
  if (J == nullptr) return PointToPlaneResidual(c, lin.T_world_imu, T_imu_lidar);
  Eigen::Matrix<double, 1, 12> h;
  const double r = PointToPlaneResidualWithExtrinsics(c, lin.T_world_imu, T_imu_lidar, &h);
  J->noalias() = h * lin.h_to_J;
  return r;
}

double PointToPlaneResidualWithTimeOffset(const Constraint& c, const FilterState& x,
                                          const ScanTimeMotion& motion, double dt_s,
                                          TimeOffsetJacobian* J) {
  return PointToPlaneResidualWithTimeOffset(c, LinearizeAtScanTime(x, motion, dt_s),
                                            x.T_imu_lidar(), J);
}

}  // namespace rvlio

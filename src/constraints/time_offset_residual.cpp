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
//     => dr/d(td) = h_theta w + h_p (v + a dt).
double PointToPlaneResidualWithTimeOffset(const Constraint& c, const FilterState& x,
                                          const ScanTimeMotion& motion, double dt_s,
                                          TimeOffsetJacobian* J) {
  const Pose3 T_world_imu = ScanTimePose(x, motion, dt_s);
  if (J == nullptr) return PointToPlaneResidual(c, T_world_imu, x.T_imu_lidar());
  Eigen::Matrix<double, 1, 12> h;
  const double r = PointToPlaneResidualWithExtrinsics(c, T_world_imu, x.T_imu_lidar(), &h);
  const Eigen::Matrix3d R_step = so3::Exp(motion.gyro_imu * dt_s);
  const Eigen::RowVector3d h_rot = h.head<3>(), h_pos = h.segment<3>(3);
  J->head<3>() = h_rot * R_step.transpose();
  J->segment<9>(3) = h.segment<9>(3);
  J->segment<3>(12) = h_pos * dt_s;
  (*J)(15) = h_rot.dot(motion.gyro_imu) +
             h_pos.dot(x.v_world_imu + motion.acc_world * dt_s);
  return r;
}

}  // namespace rvlio

#include "rvlio/constraints/point_to_plane.h"

namespace rvlio {

// Derivation (paper Eq. 3). With p_imu = R_il p_l + t_il and
// r = u^T (R_wi p_imu + t_wi - q):
//
// * Rotation of the IMU, R_wi Exp(dtheta) ~= R_wi (I + [dtheta]x):
//     dr = u^T R_wi [dtheta]x p_imu = -u^T R_wi [p_imu]x dtheta
//   and since -a^T [b]x = (b x a)^T for a = R_wi^T u, b = p_imu,
//     dr/dtheta = (p_imu x (R_wi^T u))^T.
// * Position of the IMU: dr/dp = u^T.
// * Extrinsic rotation, R_il Exp(dphi): dr = -u^T R_wi R_il [p_l]x dphi, so
//     dr/dphi = (p_l x (R_il^T R_wi^T u))^T.
// * Extrinsic translation: dr/dt = u^T R_wi = (R_wi^T u)^T.

double PointToPlaneResidual(const Constraint& c, const Pose3& T_world_imu, const Pose3& T_imu_lidar,
                            Eigen::Matrix<double, 1, 6>* J) {
  const Eigen::Vector3d p_imu = T_imu_lidar * c.p_lidar;
  const Eigen::Vector3d p_world = T_world_imu * p_imu;
  const Eigen::Vector3d& u = c.normal_world;
  if (J != nullptr) {
    const Eigen::Vector3d u_imu = T_world_imu.R.transpose() * u;
    J->leftCols<3>() = p_imu.cross(u_imu).transpose();
    J->rightCols<3>() = u.transpose();
  }
  return u.dot(p_world - c.q_world);
}

double PointToPlaneResidualWithExtrinsics(const Constraint& c, const Pose3& T_world_imu,
                                          const Pose3& T_imu_lidar,
                                          Eigen::Matrix<double, 1, 12>* J) {
  const Eigen::Vector3d p_imu = T_imu_lidar * c.p_lidar;
  const Eigen::Vector3d p_world = T_world_imu * p_imu;
  const Eigen::Vector3d& u = c.normal_world;
  if (J != nullptr) {
    const Eigen::Vector3d u_imu = T_world_imu.R.transpose() * u;
    const Eigen::Vector3d u_lidar = T_imu_lidar.R.transpose() * u_imu;
    J->block<1, 3>(0, 0) = p_imu.cross(u_imu).transpose();
    J->block<1, 3>(0, 3) = u.transpose();
    J->block<1, 3>(0, 6) = c.p_lidar.cross(u_lidar).transpose();
    J->block<1, 3>(0, 9) = u_imu.transpose();
  }
  return u.dot(p_world - c.q_world);
}

}  // namespace rvlio

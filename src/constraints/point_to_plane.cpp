#include "rvlio/constraints/point_to_plane.h"

#include <algorithm>
#include <cmath>
#include <vector>

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

ResidualStats ComputeResidualStats(const ConstraintList& constraints, const Pose3& T_world_imu,
                                   const Pose3& T_imu_lidar) {
  ResidualStats s;
  if (constraints.empty()) return s;
  std::vector<double> abs_r;
  abs_r.reserve(constraints.size());
  double sum_sq = 0.0;
  for (const Constraint& c : constraints) {
    const double r = PointToPlaneResidual(c, T_world_imu, T_imu_lidar);
    abs_r.push_back(std::abs(r));
    sum_sq += r * r;
  }
  const auto mid = abs_r.begin() + static_cast<std::ptrdiff_t>(abs_r.size() / 2);
  std::nth_element(abs_r.begin(), mid, abs_r.end());
  s.count = static_cast<int>(abs_r.size());
  s.median_abs_m = *mid;
  s.rms_m = std::sqrt(sum_sq / static_cast<double>(abs_r.size()));
  return s;
}

}  // namespace rvlio

#include "rvlio/factors/plane_time_offset_factor.h"

#include <cmath>
#include <utility>

#include <Eigen/Core>

#include "rvlio/common/check.h"
#include "rvlio/factors/parameter_blocks.h"
#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/plane_factor.h"

namespace rvlio {

using plane_summary::Matrix13d;
using plane_summary::Vector13d;

PlaneTimeOffsetFactor::PlaneTimeOffsetFactor(const ConstraintList& constraints, double sigma_m,
                                             const Pose3& T_imu_lidar,
                                             const ScanTimeMotion& motion, double td_lin_s,
                                             const Eigen::Vector3d& center_world)
    : summary_(constraints, T_imu_lidar, sigma_m, center_world),
      motion_(motion),
      td_lin_s_(td_lin_s) {
  CheckedPlaneInvSigma(constraints, sigma_m);
}

bool PlaneTimeOffsetFactor::Evaluate(double const* const* parameters, double* residuals,
                                     double** jacobians) const {
  const Pose3 T_world_imu = PoseBlock::FromArray(parameters[0]).ToPose3();
  FilterState x;
  x.R_world_imu = T_world_imu.R;
  x.p_world_imu = T_world_imu.t;
  x.v_world_imu = SpeedBiasBlock::FromArray(parameters[1]).v_world_imu;
  const ScanTimeLinearization lin = LinearizeAtScanTime(x, motion_, parameters[2][0] - td_lin_s_);
  const Matrix13d& sqrt_M = summary_.sqrt_information();
  Eigen::Map<Vector13d> r(residuals);
  r.noalias() =
      sqrt_M * plane_summary::PoseVector(lin.T_world_imu.R, lin.T_world_imu.t, summary_.center());
  if (jacobians == nullptr) return true;
  // d r / d[dtheta, dp, dphi, dt_ext, dv, d(td)]; the extrinsic columns unused.
  const Eigen::Matrix<double, 13, 16> J =
      sqrt_M * plane_summary::PoseVectorJacobian(lin.T_world_imu.R) * lin.h_to_J.topRows<6>();
  if (jacobians[0] != nullptr) {
    const Eigen::Matrix<double, 13, 6, Eigen::RowMajor> J_pose = J.leftCols<6>();
    PoseTangentToAmbientJacobian(parameters[0], J_pose, jacobians[0]);
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 13, 9, Eigen::RowMajor>> J_sb(jacobians[1]);
    J_sb.setZero();
    J_sb.middleCols<3>(SpeedBiasBlock::kVel) = J.middleCols<3>(12);
  }
  if (jacobians[2] != nullptr) Eigen::Map<Vector13d>{jacobians[2]} = J.col(15);
  return true;
}

TimeOffsetRandomWalkFactor::TimeOffsetRandomWalkFactor(double random_walk, double dt_s) {
  RVLIO_CHECK(random_walk > 0.0 && dt_s > 0.0);
  inv_sigma_ = 1.0 / (random_walk * std::sqrt(dt_s));
}

bool TimeOffsetRandomWalkFactor::Evaluate(double const* const* parameters, double* residuals,
                                          double** jacobians) const {
  residuals[0] = inv_sigma_ * (parameters[1][0] - parameters[0][0]);
  if (jacobians != nullptr) {
    if (jacobians[0] != nullptr) jacobians[0][0] = -inv_sigma_;
    if (jacobians[1] != nullptr) jacobians[1][0] = inv_sigma_;
  }
  return true;
}

}  // namespace rvlio

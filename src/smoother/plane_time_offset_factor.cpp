#include "rvlio/smoother/plane_time_offset_factor.h"

#include <cmath>
#include <utility>

#include <Eigen/Core>

#include "rvlio/common/check.h"
#include "rvlio/math/smoother_blocks.h"
#include "rvlio/smoother/manifolds.h"
#include "rvlio/smoother/plane_factor.h"

namespace rvlio {

PlaneTimeOffsetFactor::PlaneTimeOffsetFactor(ConstraintList constraints, double sigma_m,
                                             const Pose3& T_imu_lidar,
                                             const ScanTimeMotion& motion, double td_lin_s)
    : constraints_(std::move(constraints)),
      T_imu_lidar_(T_imu_lidar),
      motion_(motion),
      td_lin_s_(td_lin_s) {
  inv_sigma_ = CheckedPlaneInvSigma(constraints_, sigma_m);
  set_num_residuals(num_constraints());
  mutable_parameter_block_sizes()->push_back(PoseBlock::kNumParams);
  mutable_parameter_block_sizes()->push_back(SpeedBiasBlock::kNumParams);
  mutable_parameter_block_sizes()->push_back(1);
}

bool PlaneTimeOffsetFactor::Evaluate(double const* const* parameters, double* residuals,
                                     double** jacobians) const {
  const Pose3 T_world_imu = PoseBlock::FromArray(parameters[0]).ToPose3();
  FilterState x;
  x.R_world_imu = T_world_imu.R;
  x.p_world_imu = T_world_imu.t;
  x.v_world_imu = SpeedBiasBlock::FromArray(parameters[1]).v_world_imu;
  const ScanTimeLinearization lin = LinearizeAtScanTime(x, motion_, parameters[2][0] - td_lin_s_);
  const int n = num_constraints();
  const bool want_pose = jacobians != nullptr && jacobians[0] != nullptr;
  const bool want_sb = jacobians != nullptr && jacobians[1] != nullptr;
  const bool want_td = jacobians != nullptr && jacobians[2] != nullptr;
  const bool want_any = want_pose || want_sb || want_td;
  using RowMajorX6 = Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>;
  RowMajorX6 J_pose(want_pose ? n : 0, 6);
  using RowMajorX9 = Eigen::Matrix<double, Eigen::Dynamic, 9, Eigen::RowMajor>;
  Eigen::Map<RowMajorX9> J_sb(want_sb ? jacobians[1] : nullptr, want_sb ? n : 0, 9);
  if (want_sb) J_sb.setZero();
  TimeOffsetJacobian h;
  for (int i = 0; i < n; ++i) {
    const Constraint& c = constraints_[i];
    const double s = std::sqrt(c.weight) * inv_sigma_;
    const double r =
        PointToPlaneResidualWithTimeOffset(c, lin, T_imu_lidar_, want_any ? &h : nullptr);
    residuals[i] = s * r;
    if (want_pose) J_pose.row(i) = s * h.head<6>();
    if (want_sb) J_sb.row(i).segment<3>(SpeedBiasBlock::kVel) = s * h.segment<3>(12);
    if (want_td) jacobians[2][i] = s * h(15);
  }
  if (want_pose) PoseTangentToAmbientJacobian(parameters[0], J_pose, jacobians[0]);
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

#pragma once
// All point-to-plane constraints of one scan with the LiDAR-IMU time offset
// as a parameter (lidar.estimate_time_offset in the smoother). Blocks: the
// scan's state pose T_world_imu (PoseBlock, 7), its SpeedBiasBlock (9; the
// velocity carries the pose to the scan's time) and the window's time offset
// td (1, s).
//
// The scan was predicted and deskewed with the offset td_lin; its points
// were taken dt = td - td_lin after the state's time, at the pose
// ScanTimePose(state, motion, dt) (constraints/time_offset_residual.h), with
// the motion held at the state's time. Residual i:
//   r_i = sqrt(weight_i) / sigma * PointToPlaneResidualWithTimeOffset(c_i, ...)
// Tangent Jacobian rows: its [dtheta, dp] for the pose (ambient form of
// smoother/manifolds.h), [dv, 0, 0] for the speed-bias block, d(td).
// The extrinsic is held at the given value.
#include <ceres/cost_function.h>
#include <ceres/sized_cost_function.h>

#include "rvlio/constraints/constraint.h"
#include "rvlio/constraints/time_offset_residual.h"
#include "rvlio/math/pose.h"

namespace rvlio {

class PlaneTimeOffsetFactor final : public ceres::CostFunction {
 public:
  // constraints: non-empty, weights >= 0, unit normals. sigma_m > 0.
  PlaneTimeOffsetFactor(ConstraintList constraints, double sigma_m, const Pose3& T_imu_lidar,
                        const ScanTimeMotion& motion, double td_lin_s);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  int num_constraints() const { return static_cast<int>(constraints_.size()); }

 private:
  ConstraintList constraints_;
  double inv_sigma_ = 1.0;
  Pose3 T_imu_lidar_;
  ScanTimeMotion motion_;
  double td_lin_s_ = 0.0;
};

// The random walk of the time offset between the offset of the scans that
// leave the window (td_prev) and the window's (td), over dt_s of the
// recording (lidar.time_offset_random_walk q, s/sqrt(s)):
//   r = (td - td_prev) / (q sqrt(dt)),   dr/dtd = -dr/dtd_prev = 1 / (q sqrt(dt)).
// Blocks: td_prev (1), td (1), both s.
class TimeOffsetRandomWalkFactor final : public ceres::SizedCostFunction<1, 1, 1> {
 public:
  // random_walk > 0, dt_s > 0.
  TimeOffsetRandomWalkFactor(double random_walk, double dt_s);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  double inv_sigma_ = 1.0;  // 1 / (q sqrt(dt))
};

}  // namespace rvlio

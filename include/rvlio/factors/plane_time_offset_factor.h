#pragma once
// All point-to-plane constraints of one scan with the LiDAR-IMU time offset
// as a parameter (lidar.estimate_time_offset in the smoother). Blocks: the
// scan's state pose T_world_imu (PoseBlock, 7), its SpeedBiasBlock (9; the
// velocity carries the pose to the scan's time) and the window's time offset
// td (1, s).
//
// The scan was predicted and deskewed with the offset td_lin; its points
// were taken dt = td - td_lin after the state's time, at the pose
// T_scan = ScanTimePose(state, motion, dt) (constraints/time_offset_residual.h),
// with the motion held at the state's time. Each residual
//   sqrt(weight_i) / sigma * PointToPlaneResidualWithTimeOffset(c_i, ...)
// is linear in z(T_scan) of PlaneSummaryFactor (plane_summary_factor.h), so
// the scan is summarized the same way, exactly, in 13 residuals
//   r = L^1/2 V^T z(T_scan)
// at a cost independent of the number of points; the Jacobian chains the
// summary's d z / d[d_rot, d_pos] at T_scan with the scan-time
// linearization (ScanTimeLinearization::h_to_J, top rows): pose
// [dtheta, dp], speed-bias [dv, 0, 0], offset d(td). J^T J and J^T r equal
// those of the per-point residuals. The extrinsic is held at the given value.
#include <ceres/cost_function.h>
#include <ceres/sized_cost_function.h>

#include "rvlio/constraints/constraint.h"
#include "rvlio/constraints/time_offset_residual.h"
#include "rvlio/math/pose.h"
#include "rvlio/factors/plane_summary_factor.h"

namespace rvlio {

class PlaneTimeOffsetFactor final : public ceres::SizedCostFunction<13, 7, 9, 1> {
 public:
  // constraints: non-empty, weights >= 0, unit normals. sigma_m > 0.
  // center_world: any point, ideally near the scan (conditioning only).
  PlaneTimeOffsetFactor(const ConstraintList& constraints, double sigma_m,
                        const Pose3& T_imu_lidar, const ScanTimeMotion& motion, double td_lin_s,
                        const Eigen::Vector3d& center_world);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  int num_constraints() const { return summary_.num_constraints(); }
  // Whether the summary is usable (finite): see PlaneSummaryFactor::information.
  bool finite() const { return summary_.information().allFinite(); }

 private:
  PlaneSummaryFactor summary_;
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

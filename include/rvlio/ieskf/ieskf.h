#pragma once
// Iterated error-state Kalman filter on the 24-dim manifold of paper
// Section 2 (FAST-LIO2 structure): per-sample IMU propagation of state and
// covariance, and the iterated point-to-plane update of paper Eq. (1) with
// re-association and the RV modules inside every iteration (Alg. 3).
#include <array>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <vector>

#include "rvlio/common/types.h"
#include "rvlio/constraints/constraint.h"
#include "rvlio/constraints/options.h"
#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/constraints/time_offset_residual.h"
#include "rvlio/degeneracy/degeneracy.h"
#include "rvlio/degeneracy/options.h"
#include "rvlio/ieskf/options.h"
#include "rvlio/imu/options.h"
#include "rvlio/imu/pose_history.h"
#include "rvlio/lidar/options.h"
#include "rvlio/math/extrinsic_excitation.h"
#include "rvlio/imu/filter_state.h"
#include "rvlio/rv/options.h"
#include "rvlio/rv/rv.h"

namespace rvlio {

// Builds the constraint list of the scan for a given state: association
// against the map (supplied by the pipeline, so the filter owns no map).
using AssociateFn = std::function<void(const FilterState&, ConstraintList*)>;

struct IeskfUpdateResult {
  bool ok = false;            // false: no usable constraints or diverged (state untouched)
  bool diverged = false;      // non-finite or exploding covariance: reset to the prior
  int iterations = 0;
  int num_constraints = 0;    // of the last iteration
  double last_step_norm = 0.0;
  RvReport rv;                // of the last iteration
  DegeneracyReport degeneracy;  // of the last iteration (degeneracy/degeneracy.h)
  // For the divergence monitor (odometry/divergence.h); no effect on the update.
  // Normalized innovation squared of the first iteration's constraints at the
  // prediction, z^T (H P H^T + R)^-1 z / n (Woodbury form); NaN if no iteration.
  double nis_per_dof = std::numeric_limits<double>::quiet_NaN();
  // The rotation (rad, IMU frame: R_world_imu * Exp(it)) the first
  // iteration's constraints alone ask of the prediction: one Gauss-Newton
  // step in the rotation, position held, no prior. Small when the gyro and
  // the LiDAR agree; a wrong extrinsic rotation (an upside-down mount) makes
  // every turn of the platform look turned the other way to the LiDAR, a
  // clock offset tau makes it about tau times the change of the rotation rate
  // (odometry/divergence.h). NaN if no iteration.
  Eigen::Vector3d lidar_rotation_imu = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  ResidualStats residuals;    // last iteration's constraints at the updated state (ok only)
};

// The error-state rows (FilterState offsets) of the 12 columns of
// PointToPlaneResidualWithExtrinsics()'s Jacobian [dtheta, dp, dphi, dt]:
// the error-state Jacobian of a residual is h * ErrorStateColumns(free)^T.
// Extrinsic axes with free[i] false get no row (held fixed).
Eigen::Matrix<double, 24, 12> ErrorStateColumns(const std::array<bool, 6>& free_extrinsic_axes);

// The LiDAR-IMU time offset as the filter holds it: with
// lidar.estimate_time_offset an augmented state (TimeOffsetState of the
// update, src/ieskf/state_policies.h), else the configured offset, no variance.
struct TimeOffsetEstimate {
  double td_s = 0.0;           // the estimate, s
  double td_lin_s = 0.0;       // the offset the last scan was predicted and deskewed with
  ScanTimeMotion scan_motion;  // the motion held at the last updated scan's state time
  Vector24d P_x_td = Vector24d::Zero();  // cross covariance with the 24-dim error state
  double P_td_td = 0.0;        // variance, s^2
  bool observed = false;       // the last update estimated the offset (not at rest)
};

struct ExtrinsicColumns;

class Ieskf {
 public:
  // `lidar`: the time-offset keys (estimate_time_offset and its noise, bound).
  // `degeneracy`: the treatment of weak directions; RV runs only with method rv.
  Ieskf(const IeskfOptions& options, const ImuOptions& imu, const ConstraintOptions& constraints,
        const RvOptions& rv, const LidarOptions& lidar = LidarOptions(),
        const DegeneracyOptions& degeneracy = DegeneracyOptions());

  // Starts the filter at t_ns from a static alignment; P from the init stds.
  void Initialize(const FilterState& x0, TimeNs t_ns, const ImuSample& last_imu);

  // One IMU sample: propagates state and covariance from the current time to
  // the sample's time (midpoint of the held and the new measurement).
  void Propagate(const ImuSample& imu);
  // Propagates to t_ns holding the last IMU measurement (scan end).
  void PropagateTo(TimeNs t_ns);

  // Pose samples recorded by propagation since the last ClearPoseHistory()
  // (imu/pose_history.h); the first entry is the state at the time of clearing.
  const std::vector<ImuPoseSample>& pose_history() const { return pose_history_.samples(); }
  void ClearPoseHistory();

  // A rigid change of world frame (localization in a reference map,
  // odometry/reference.h): pose, velocity and gravity are carried into the
  // new frame by T_new_old, and the world-frame blocks of P (position,
  // velocity, gravity) rotate with them; the pose history is cleared.
  void ChangeWorldFrame(const Pose3& T_new_old);

  // Iterated update, paper Eq. (1): re-associates, applies RV, solves.
  IeskfUpdateResult Update(const AssociateFn& associate);

  const FilterState& state() const { return x_; }
  const Matrix24d& covariance() const { return P_; }
  // Excitation of the extrinsic block (estimate_extrinsics; see
  // math/extrinsic_excitation.h): an axis takes part in the update only once
  // excited, judged on the covariance the updates would leave with all six
  // axes estimated (propagated and updated alongside P).
  const ExtrinsicExcitation& extrinsic_excitation() const { return excitation_; }
  void CountExcitationScan() {
    excitation_.CountScan(t_ns_, x_.R_world_imu, x_.R_imu_lidar);
  }
  TimeNs time_ns() const { return t_ns_; }

  // The LiDAR-IMU time offset (lidar.time_offset, or its online estimate), s.
  double time_offset_s() const { return td_.td_s; }
  // Its 1-sigma (0 when not estimated).
  double time_offset_std_s() const;
  // True while the estimate is held at +-lidar.time_offset_max (an update
  // pushed it there or past it).
  bool time_offset_at_bound() const {
    return lidar_.estimate_time_offset && std::abs(td_.td_s) >= lidar_.time_offset_max;
  }
  // True when the last update estimated the offset: the motion showed it
  // (not at rest; estimate_time_offset only).
  bool time_offset_observed() const { return td_.observed; }
  // True when a scan predicted to t_end_ns from the current state would show
  // the offset (the test Update applies; const: the filter is not moved).
  bool TimeOffsetObservableAt(const std::deque<ImuSample>& imu, TimeNs t_end_ns) const;
  // Sets the offset's estimate and 1-sigma, uncorrelated with the rest of the
  // state (lidar.time_offset_replay: the converged estimate at the snapshot).
  void SetTimeOffset(double td_s, double std_s);
  // The IMU pose at the time of the last updated scan (the state's pose when
  // the offset is not estimated; see ScanTimeMotion).
  Pose3 ScanTimeImuPose() const {
    return ScanTimePose(x_, td_.scan_motion, td_.td_s - td_.td_lin_s);
  }

 private:
  // The update of paper Eq. (1) with the optional states of StatePolicy
  // (NoTimeOffsetState or TimeOffsetState, src/ieskf/state_policies.h).
  template <class StatePolicy>
  IeskfUpdateResult UpdateImpl(const AssociateFn& associate);
  // The optional state's policy, chosen once from lidar.estimate_time_offset:
  // how it starts, propagates and updates (src/ieskf/state_policies.h).
  struct StateKind {
    void (*start)(const LidarOptions& lidar, TimeOffsetEstimate* td);
    void (*propagate)(const Matrix24d& F, double dt_s, const LidarOptions& lidar,
                      TimeOffsetEstimate* td);
    IeskfUpdateResult (Ieskf::*update)(const AssociateFn& associate);
  };
  template <class StatePolicy>
  static StateKind KindOf();
  ExtrinsicColumns ExtrinsicColumnsNow() const;
  ScanTimeMotion MotionAtStateTime() const;
  void Step(const Eigen::Vector3d& gyro_imu, const Eigen::Vector3d& acc_imu, double dt_s);
  void RecordPose(const Eigen::Vector3d& gyro_imu, const Eigen::Vector3d& acc_imu);
  void ReleaseExcitedAxes();
  void AddExtrinsicRandomWalk(double dt_s);
  void UpdateExcitation(const Eigen::Matrix<double, 12, 12>& HtRinvH, const Matrix24d& J);

  IeskfOptions options_;
  ImuOptions imu_;
  ConstraintOptions constraints_;
  RvOptions rv_;  // EffectiveRvOptions: enabled only with degeneracy method rv
  DegeneracyOptions degeneracy_;
  FilterState x_;
  Matrix24d P_ = Matrix24d::Identity();
  Matrix24d P_all_extrinsic_ = Matrix24d::Identity();  // as P_, every extrinsic axis estimated
  ExtrinsicExcitation excitation_;
  std::array<bool, 6> released_{};  // extrinsic axes given their prior variance in P_
  TimeNs t_ns_ = 0;
  ImuSample last_imu_;
  ImuPoseHistory pose_history_;
  RvWorkspace rv_workspace_;
  LidarOptions lidar_;
  StateKind state_kind_;
  TimeOffsetEstimate td_;
};

}  // namespace rvlio

#pragma once
// The sliding window of the smoother backend (docs/design.md "The backends").
//
// One state per scan, at the scan's end time: a PoseBlock (7, PoseManifold)
// and a SpeedBiasBlock (9) (factors/parameter_blocks.h). The cost of a solve:
//   - an ImuFactor between consecutive states (imu_factor.h), preintegrated
//     from the IMU samples between their times and re-integrated when the
//     bias estimate of the earlier state moved far from its linearization
//     point; across an IMU gap (no preintegration) a weak
//     SpeedBiasContinuityFactor instead (prior_factor.h);
//   - one plane factor per state with that scan's point-to-plane constraints
//     (PlaneSummaryFactor: PlaneFactor's cost in 13 exact residuals,
//     plane_summary_factor.h; its kind, chosen once from the options, makes
//     it and names its blocks: src/window/scan_factor.h). Per-point information = Constraint::weight / sigma^2
//     with weight = (RV: 1/K for SCVs, rv/rv.h) x (Huber IRLS weight
//     min(1, sliding_window_huber_delta / |r|) at the pose of association);
//   - with degeneracy.method localizability or regularized (and remap in
//     its hold form), a PosePriorFactor per state along the weak directions
//     its scan's constraints leave (degeneracy/degeneracy.h
//     DegeneracyPriorSqrtInformation), anchored at the state's initial value
//     (the IMU prediction); not marginalized (a statement about the solve,
//     not information: docs/degeneracy.md). With remap (project form) the
//     plane factor instead has no say along those directions
//     (factors/pose_projected_factor.h). Analyzed at each association, at
//     the scan's pose of that association, with the weights before Huber;
//   - the prior on the oldest state: a StatePriorFactor on the first state of
//     the run, then the marginalization prior (marginalization.h), whose
//     Jacobian stays at its linearization point (first-estimate Jacobians).
//
// Optimize() runs smoother.association_rounds rounds of
//   associate (every state that moved more than reassociate_min_motion since
//   its last association, and every state never associated) -> RV -> Huber
//   weights -> Ceres solve (max_solver_iterations).
// A round after the first that associates no scan ends Optimize (its solve
// would repeat the previous round's problem), unless
// smoother.solve_unchanged_rounds.
// A round whose solve fails or yields non-finite (or absurd: speed above
// max_speed) values restores the states from before that round (counted) and
// invalidates the associations. The round is then redone once without the
// newest state's IMU factor (a corrupt burst of IMU samples is the usual
// culprit; the weak continuity prior replaces it, counted as skipped); if it
// fails again, Optimize ends with the last good states.
// MarginalizeIfFull() removes the oldest state through the Schur complement
// once the window holds window_size states and hands its final estimate and
// points back (for the map).
//
// With smoother.estimate_extrinsics the extrinsic T_imu_lidar is one more
// parameter block (PoseBlock, PoseManifold) shared by every scan's plane
// factor (PlaneExtrinsicFactor instead of the summary). Its prior
// (PosePriorFactor at the configured extrinsics, smoother.extrinsic_*_std) enters
// the first marginalization; from then on the extrinsic is a kept block of
// the marginalization prior, which carries the information of every scan that
// left the window (the same Schur complement, no double counting). Its
// excitation (math/extrinsic_excitation.h) is judged on that prior's marginal
// covariance of the extrinsic block: an axis not yet excited is held fixed
// (PoseSubsetManifold; all fixed: a constant block).
//
// With lidar.estimate_time_offset the LiDAR-IMU time offset is one more
// parameter block (1, s), shared by every scan's plane factor
// (PlaneTimeOffsetFactor: the scan's pose is its state's carried over
// td - td_lin by the motion held at the state, plane_time_offset_factor.h).
// As with the extrinsic, its prior (lidar.time_offset, time_offset_init_std)
// enters the first marginalization and the offset is then a kept block of the
// marginalization prior. At each marginalization the offset of the leaving
// scan is tied to the window's by a random walk (lidar.time_offset_random_walk,
// TimeOffsetRandomWalkFactor), so the prior holds it with a variance grown by
// q^2 dt. An estimate past lidar.time_offset_max is held at the bound and
// reported (time_offset_at_bound()).
//
// The window owns no map: association is a callback, so the window can be
// driven by the odometry's voxel map or by an exact synthetic world.
#include <cmath>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <ceres/types.h>

#include "rvlio/common/options.h"
#include "rvlio/common/time.h"
#include "rvlio/constraints/constraint.h"
#include "rvlio/constraints/options.h"
#include "rvlio/degeneracy/degeneracy.h"
#include "rvlio/degeneracy/options.h"
#include "rvlio/ieskf/options.h"
#include "rvlio/imu/options.h"
#include "rvlio/imu/noise.h"
#include "rvlio/imu/preintegration.h"
#include "rvlio/lidar/extrinsics.h"
#include "rvlio/lidar/options.h"
#include "rvlio/constraints/time_offset_residual.h"
#include "rvlio/math/extrinsic_excitation.h"
#include "rvlio/math/pose.h"
#include "rvlio/factors/parameter_blocks.h"
#include "rvlio/rv/options.h"
#include "rvlio/rv/rv.h"
#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/marginalization.h"
#include "rvlio/window/options.h"
#include "rvlio/factors/prior_factor.h"

namespace ceres {
class Problem;
}  // namespace ceres

namespace rvlio {

class ImuFactor;
class ScanFactorKind;

// The window's configuration: the option sections it reads, with the names
// and types they have in the odometry's options (OdometryOptions), listed in
// Visit so that the odometry fills them through the options reflection
// (CopySections, common/options.h) and validation names their keys; plus the
// gravity of the static initialization, which is not configuration.
struct WindowOptions {
  SmootherOptions smoother;       // window_size, rounds, iterations, sliding_window_huber_delta, ...
  RvOptions rv;                   // the same switches and parameters as the filter
  DegeneracyOptions degeneracy;   // method and parameters (the per-scan degeneracy prior)
  ImuOptions imu;                 // noise densities of the preintegration (re-integration)
  ConstraintOptions constraints;  // lidar_noise: sigma of one point-to-plane residual
  IeskfOptions ieskf;             // init_*_std: prior of the run's first state (the same static
                                  // initialization as the filter)
  ExtrinsicsSection extrinsics;   // T_imu_lidar: fixed, or the prior (smoother.estimate_extrinsics)
  LidarOptions lidar;             // time_offset: fixed, or the prior (estimate_time_offset)
  Eigen::Vector3d g_world = Eigen::Vector3d(0.0, 0.0, -9.81);  // m/s^2, static initialization

  template <class V>
  void Visit(V& v) {
    v.Section("smoother", smoother);
    v.Section("rv", rv);
    v.Section("degeneracy", degeneracy);
    v.Section("imu", imu);
    v.Section("constraints", constraints);
    v.Section("ieskf", ieskf);
    v.Section("extrinsics", extrinsics);
    v.Section("lidar", lidar);
  }
  Status Validate() { return ValidateFields(*this); }
};

// Ceres' solver type for smoother.linear_solver (a validated choice).
ceres::LinearSolverType WindowLinearSolver(const std::string& name);

// Fills *out (cleared first) with the point-to-plane constraints of the
// deskewed points p_lidar (LiDAR frame at the state's time) at T_world_imu:
// the association against the map (constraints/plane_association.h).
using ScanAssociateFn = std::function<void(const std::vector<Eigen::Vector3d>& p_lidar,
                                           const Pose3& T_world_imu, ConstraintList* out)>;

// A state's current estimate.
struct WindowState {
  TimeNs t_ns = 0;
  PoseBlock pose;             // T_world_imu
  SpeedBiasBlock speed_bias;  // v_world_imu, b_g, b_a
};

struct WindowSolveReport {
  bool ok = true;               // false: the states were restored to the last good ones
  int rounds = 0;               // rounds solved successfully
  int failures = 0;             // rounds whose solve failed or diverged (each restored)
  bool dropped_newest_imu = false;  // a failed round was redone without the newest IMU factor
  int iterations = 0;           // Ceres iterations over all rounds
  int associations = 0;         // scans (re-)associated over all rounds
  int newest_constraints = 0;   // constraints of the newest state (last association)
  RvReport newest_rv;           // RV report of the newest state (last association)
  // The degeneracy report of the newest state (last association) for
  // remap, localizability and regularized; rv and none report from newest_rv.
  DegeneracyReport newest_degeneracy;
  // sum w u u^T of the newest state's constraints (sigma = 1; rv/rv.h PositionInformation).
  Eigen::Matrix3d newest_position_information = Eigen::Matrix3d::Zero();
  double association_ms = 0.0;  // thread CPU time in association, RV and weights
  double solve_ms = 0.0;        // thread CPU time in problem building and Ceres
};

struct WindowStats {
  int64_t imu_factors_skipped = 0;       // states without an IMU factor (gap, or dropped)
  int64_t solve_failures = 0;            // rounds restored to the last good states
  int64_t marginalizations = 0;
  int64_t marginalization_failures = 0;  // replaced by a StatePriorFactor
  int64_t repropagations = 0;            // preintegrations re-integrated
  int64_t rejected_scans = 0;            // associations whose summary overflowed: no plane factor
};

// The oldest state leaving the window, at its final estimate.
struct MarginalizedScan {
  WindowState state;
  Pose3 scan_T_world_imu;  // the IMU pose at the scan's time (ScanTimeImuPose)
  std::vector<Eigen::Vector3d> p_lidar;  // the scan's deskewed points
};

class SlidingWindow {
 public:
  explicit SlidingWindow(const WindowOptions& options);
  ~SlidingWindow();
  SlidingWindow(const SlidingWindow&) = delete;
  SlidingWindow& operator=(const SlidingWindow&) = delete;

  // Clears the window and starts it with the first state of a run, held by
  // a StatePriorFactor at the given values (std: ieskf.init_*_std).
  void Start(TimeNs t_ns, const PoseBlock& pose, const SpeedBiasBlock& speed_bias,
             std::vector<Eigen::Vector3d> p_lidar);

  // Appends the newest state at t_ns >= newest time, initialized at
  // (pose, speed_bias) (the IMU prediction). imu: the preintegration from
  // the newest state's time to t_ns; nullopt, dt = 0 or non-finite values
  // add the state without an IMU factor (weak continuity prior, counted).
  // motion: the IMU motion held at t_ns (used with an estimated time offset:
  // the scan was deskewed with the current time_offset_s()).
  void Add(TimeNs t_ns, const PoseBlock& pose, const SpeedBiasBlock& speed_bias,
           std::optional<ImuPreintegration> imu, std::vector<Eigen::Vector3d> p_lidar,
           const ScanTimeMotion& motion = ScanTimeMotion());

  // Association rounds and solves (see the header comment).
  WindowSolveReport Optimize(const ScanAssociateFn& associate);

  // With window_size states: marginalizes the oldest one and returns it.
  std::optional<MarginalizedScan> MarginalizeIfFull();

  int size() const { return static_cast<int>(nodes_.size()); }
  bool empty() const { return nodes_.empty(); }
  // k = 0 is the oldest, size() - 1 the newest.
  WindowState state(int k) const;
  const std::vector<Eigen::Vector3d>& points(int k) const;
  const ConstraintList& constraints(int k) const;
  bool has_imu_factor(int k) const;  // between states k - 1 and k
  const WindowStats& stats() const { return stats_; }
  // The extrinsic in use: the estimate (estimate_extrinsics) or the configured one.
  Pose3 T_imu_lidar() const;
  const ExtrinsicExcitation& extrinsic_excitation() const { return excitation_; }
  // The time offset in use (s): the estimate (lidar.estimate_time_offset) or
  // lidar.time_offset; whether the estimate is held at +-lidar.time_offset_max
  // (a solve pushed it there or past it).
  double time_offset_s() const { return time_offset_[0]; }
  bool time_offset_at_bound() const {
    return estimate_time_offset() && std::abs(time_offset_[0]) >= options_.lidar.time_offset_max;
  }
  // The marginal 1-sigma of the offset under the marginalization prior (s;
  // the prior's std before the first marginalization, 0 when not estimated).
  double time_offset_std_s() const { return time_offset_std_s_; }
  // The IMU pose at the scan time of state k (its own pose unless the time
  // offset is estimated).
  Pose3 ScanTimeImuPose(int k) const;
  // One processed scan: the newest state's attitude feeds the rotational excitation.
  void CountExcitationScan();
  const WindowOptions& options() const { return options_; }

 private:
  struct Node;

  static std::unique_ptr<Node> MakeNode(TimeNs t_ns, const PoseBlock& pose,
                                        const SpeedBiasBlock& speed_bias,
                                        std::vector<Eigen::Vector3d> p_lidar);
  int AssociateRound(const ScanAssociateFn& associate, WindowSolveReport* report);
  void AssociateNode(const ScanAssociateFn& associate, Node* node);
  void RejectOverflowingScan(Node* node);
  LeastSquaresDegeneracy AnalyzeNodeDegeneracy(const Pose3& T_world_imu, const Pose3& T_imu_lidar,
                                               const Node& node) const;
  void TreatDegeneracy(const LeastSquaresDegeneracy& d, Node* node) const;
  void ClearDegeneracy(Node* node) const;
  bool PoseTied(size_t k) const;
  std::vector<double*> ScanBlocks(Node* node, double* time_offset);
  void RefreshImuFactors();
  void ResetCalibrationPriors();
  bool DropNewestImuFactor();
  bool SolveRound(WindowSolveReport* report);
  bool Healthy() const;
  bool estimate_extrinsics() const { return options_.smoother.estimate_extrinsics; }
  bool estimate_time_offset() const { return options_.lidar.estimate_time_offset; }
  Pose3 ScanPose(const Node& node) const;
  void HoldTimeOffsetInBound();
  void ObserveTimeOffsetStd();
  void AddExtrinsicBlock(ceres::Problem* problem);
  void ObserveExtrinsicExcitation();
  void Backup();
  void Restore();

  WindowOptions options_;
  Pose3 T_imu_lidar_config_;    // options_.extrinsics
  StatePriorStd first_prior_;   // options_.ieskf.init_*_std
  PoseManifold pose_manifold_;
  std::unique_ptr<ScanFactorKind> scan_factor_kind_;  // the plane factor of every scan
  std::deque<std::unique_ptr<Node>> nodes_;
  std::unique_ptr<StatePriorFactor> state_prior_;        // on nodes_[0], or null
  std::unique_ptr<MarginalizationFactor> marginal_prior_;  // on nodes_[0], or null
  std::vector<double> backup_;
  double extrinsic_[PoseBlock::kNumParams] = {0, 0, 0, 1, 0, 0, 0};  // T_imu_lidar
  std::unique_ptr<PosePriorFactor> extrinsic_prior_;  // until the first marginalization
  std::unique_ptr<PoseSubsetManifold> extrinsic_manifold_;  // partly excited extrinsic
  ExtrinsicExcitation excitation_;
  double time_offset_[1] = {0.0};                      // s
  std::unique_ptr<ceres::CostFunction> time_offset_prior_;  // until the first marginalization
  double time_offset_std_s_ = 0.0;
  RvWorkspace rv_workspace_;
  WindowStats stats_;
};

}  // namespace rvlio

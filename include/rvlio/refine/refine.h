#pragma once
// Offline batch refinement of a whole sequence (docs/design.md "The backends",
// "refine"; `rvlio refine`). No I/O: the caller reads the bag and writes the
// outputs.
//
// Input: every scan (downsampled, with per-point times), every IMU sample and
// an initial trajectory (T_world_imu, e.g. `rvlio run`'s trajectory.tum).
//
// Initialization. Each scan's end pose is interpolated from the initial
// trajectory (linear / slerp); scans outside its time span, scans not covered
// by IMU data and scans with too few points are dropped and counted. Initial
// velocities: central differences of the initial trajectory; biases: gyro
// bias from the static alignment of the first imu.init_duration of samples
// (imu/static_init.h), accelerometer bias zero; then one IMU-only solve (poses
// held) makes velocities and biases consistent with the IMU.
// Gravity is held fixed. Assumption: the initial trajectory's world frame is
// the one its first pose is expressed in. With a static start the gravity
// vector is the static alignment's (measured magnitude) rotated into that
// world frame by the initial trajectory's attitude at the static interval, so
// any world frame works; with a moving start (no alignment possible) the world
// frame must be gravity-aligned, z up (docs/design.md "Conventions", which is what
// `rvlio run` writes), and g_world = (0, 0, -imu.gravity).
//
// Each outer round (refine.rounds):
//   Deskew   every scan with the current estimate (IMU integrated backwards
//            from the scan-end state: refine/states.h);
//   Map      one leave-one-out map of all scans' world points at the current
//            estimates (refine/map.h): a scan never matches its own points;
//   Associate every scan against the others' points (threads over scans);
//   RV       per scan when rv.enabled (rv/rv.h: 1/K on SCVs, normal repair),
//            then Huber IRLS weights (refine.huber_delta) folded into the
//            constraint weights;
//   Degeneracy per scan with degeneracy.method remap, localizability or
//            regularized: the weak directions of its constraints at the
//            round's estimate (degeneracy/degeneracy.h) and a prior along
//            them at the scan's initial pose (from --init), added to the
//            chunk's problem;
//   Solve    one Ceres problem per chunk: PoseBlock + SpeedBiasBlock per
//            scan, ImuFactor between consecutive scans (preintegrated at the
//            current biases), and the scan's point-to-plane constraints: a
//            plane fitted mostly to scan j's points moves with scan j
//            (ScanPairPlaneFactor, refine/pair_factor.h) when j is in the
//            chunk and |k - j| <= refine.plane_window, otherwise it
//            is world-fixed (one PlaneFactor per scan, at the current estimate
//            of its source scan). Attached planes make each round a joint
//            optimization over the associations: with world-fixed planes only
//            (window 0) a drift shared by the scans decays only slowly from
//            round to round. The window bounds the fill-in of the sparse
//            Cholesky factor (docs/refine.md). The first pose is held fixed (gauge); linear
//            solver SPARSE_NORMAL_CHOLESKY with SuiteSparse CHOLMOD (Eigen's
//            sparse Cholesky if Ceres lacks SuiteSparse;
//            RefineResult::linear_solver says which);
//            refine.solver_iterations LM iterations.
// Rounds stop early when no pose moved more than 0.5 mm / 0.005 deg.
//
// Long sequences: chunks of refine.chunk_scans scans overlapping by
// 10% (at least 2 scans); each chunk after the first holds its first pose at
// the previous chunk's result. The map always spans the whole sequence.
//
// A solve that fails or produces non-finite values restores the chunk's
// states from before the solve and is counted; the output never holds NaN.
//
// The steps, each with its own header: refine/init.h (state
// initialization), refine/association.h (deskew, map, association round),
// refine/problem.h (problem build and solve), refine/chunks.h (chunking);
// how they fit, what they hold and cost: docs/refine.md.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/constraints/options.h"
#include "rvlio/degeneracy/options.h"
#include "rvlio/imu/options.h"
#include "rvlio/lidar/preprocess.h"
#include "rvlio/map/map_cloud.h"
#include "rvlio/map/options.h"
#include "rvlio/map/voxel_map.h"
#include "rvlio/math/pose.h"
#include "rvlio/rv/options.h"
#include "rvlio/refine/control.h"
#include "rvlio/refine/options.h"
#include "rvlio/refine/states.h"

namespace rvlio {

struct RefineConfig {
  ImuOptions imu;
  Pose3 T_imu_lidar;  // extrinsics, fixed
  MapOptions map;
  ConstraintOptions constraints;
  RvOptions rv;
  // degeneracy.method remap, localizability, regularized: per scan and
  // round, a prior at the scan's initial (--init) pose along the weak
  // directions of its constraints (docs/degeneracy.md "Backends").
  DegeneracyOptions degeneracy;
  RefineOptions refine;
  // A fixed reference map (`refine --map`, docs/survey.md), or null. Each
  // scan is then also associated with it every round (the same association
  // and Huber weights), its planes world-fixed, so the result is held to the
  // reference's frame; the first scan's pose is then not held (no gauge
  // freedom is left).
  std::shared_ptr<const VoxelMap> reference;
  // Survey ties (`refine --control`, GNSS; refine/control.h, docs/control.md),
  // survey.ties:
  // a PositionFactor each in every chunk that holds its state(s), in the
  // frame of the initial trajectory; a chunk holding one does not hold its
  // first pose (the ties fix the gauge), as with a reference.
  // With rest_sigma_v > 0, every state inside one of the rests of the
  // stop-and-go marks gets a ZeroVelocityFactor (control.rest_sigma_v).
  SurveyFactors survey;
};

struct RefineInput {
  std::vector<Scan> scans;     // downsampled, LiDAR frame, per-point times; sorted by t_end_ns
  std::vector<ImuSample> imu;  // sorted by time
  Trajectory init;             // T_world_imu, sorted by time
};

// The convergence report of one outer round (summed over chunks).
struct RefineRound {
  int round = 0;  // 1-based
  int chunks = 0;
  double cost_before = 0.0;  // Ceres cost 1/2 |r|^2 at the start of the solves
  double cost_after = 0.0;
  int iterations = 0;        // Ceres iterations, summed over chunks
  double max_translation_change_m = 0.0;  // largest pose change of any scan in this round
  double max_rotation_change_deg = 0.0;
  int64_t points = 0;       // deskewed scan points associated
  int64_t constraints = 0;  // accepted point-to-plane constraints
  int rv_active_scans = 0;
  int degenerate_scans = 0;  // scans degeneracy.method called degenerate (rv: RV active)
  int solve_failures = 0;   // chunks whose solve was rejected (states restored)
  double deskew_s = 0.0, map_s = 0.0, associate_s = 0.0, solve_s = 0.0, total_s = 0.0;  // wall
};

struct RefineStats {
  int64_t scans_input = 0;
  int64_t scans_outside_init = 0;    // end time outside the initial trajectory's span
  int64_t scans_without_imu = 0;     // not covered by IMU samples
  int64_t scans_too_few_points = 0;  // fewer than kRefineMinScanPoints points
  int64_t scans_out_of_order = 0;    // end time not after the previous kept scan's
  int64_t scans_refined = 0;
  int64_t imu_samples = 0;
  int64_t map_entries = 0;  // leave-one-out map of the last round
  int chunks = 0;
  bool gravity_from_static = false;  // false: (0, 0, -imu.gravity), see the header comment
  bool started_moving = false;       // the static alignment saw motion
};

struct RefineResult {
  Trajectory trajectory;  // refined T_world_imu at every refined scan's end
  std::vector<Eigen::Vector3d> v_world_imu, gyro_bias, accel_bias;  // per refined scan
  // The output map (map.output_resolution) at the result: every refined
  // scan re-projected with its refined pose, each point with its return's
  // attributes; scan_index is the refined scan's row in `trajectory`.
  MapCloud map;
  std::vector<RefineRound> rounds;
  RefineStats stats;
  Eigen::Vector3d g_world = Eigen::Vector3d(0.0, 0.0, -9.81);
  std::string linear_solver;  // e.g. "SPARSE_NORMAL_CHOLESKY (SUITE_SPARSE)"
  int threads = 1;
  bool converged = false;     // stopped on the pose-change threshold before the round cap
  bool stopped = false;       // RefineHooks::stop ended it: the last completed round's result
  double init_solve_s = 0.0;  // the IMU-only velocity and bias solve
  double total_s = 0.0;       // wall time of Refine()
  std::vector<std::string> warnings;
};

constexpr int kRefineMinScanPoints = kMinScanPoints;  // the odometry's floor (lidar/preprocess.h)

// Called after each round (e.g. to print the convergence line).
using RefineRoundCallback = std::function<void(const RefineRound&)>;

// What a completed round hands to the next one: everything a refinement
// started from it (RefineHooks::resume) needs to end with the result of an
// uninterrupted run, bit for bit (the input and the configuration being the
// same). The rest (map, associations, deskewed points) is rebuilt from these
// each round.
struct RefineRoundState {
  int rounds_done = 0;  // 0: the initialization (velocity and bias solve) only
  bool converged = false;
  std::vector<RefineState> states;  // per refined scan
  Eigen::Vector3d g_world = Eigen::Vector3d(0.0, 0.0, -9.81);
  std::vector<RefineRound> rounds;  // the reports of the rounds done
  std::vector<std::string> warnings;
  double init_solve_s = 0.0;
  int64_t map_entries = 0;  // RefineStats of the last round
  int chunks = 0;
};

struct RefineHooks {
  RefineRoundCallback on_round;  // after each round, with its report
  // After each completed round, with the state to continue from (e.g. to
  // write a checkpoint). An error ends the refinement with that status.
  std::function<Status(const RefineRoundState&)> on_state;
  // Polled between the steps of a round and between solver iterations: true
  // ends the refinement with the result of the last completed round
  // (RefineResult::stopped); a round in progress is dropped.
  std::function<bool()> stop;
  // Continue from this state (rounds_done + 1 onwards) instead of
  // initializing from RefineInput::init; InvalidInput if its states are not
  // those of this input's refined scans.
  const RefineRoundState* resume = nullptr;
};

// Refines the trajectory. InvalidInput when there is nothing to refine (no
// scans, no IMU samples, no initial poses, or fewer than 2 usable scans, e.g.
// an initial trajectory that does not overlap the scans; the message gives
// both time spans). The input is consumed (moved from) to save memory.
StatusOr<RefineResult> Refine(const RefineConfig& config, RefineInput input,
                              const RefineRoundCallback& on_round = nullptr);
StatusOr<RefineResult> Refine(const RefineConfig& config, RefineInput input,
                              const RefineHooks& hooks);

}  // namespace rvlio

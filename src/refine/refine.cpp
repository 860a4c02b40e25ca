// Batch refinement: Deskew -> Map -> Associate -> RV -> Solve, a few rounds
// (see refine.h). This file runs the rounds; the steps are
//   refine/init.h         state initialization (scans, gravity, states),
//   refine/association.h  the association round (deskew, map, plane factors),
//   refine/problem.h      problem build and solve (chunks, IMU-only solve),
//   refine/chunks.h       the chunks of a round.
#include "rvlio/refine/refine.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <utility>

#include "rvlio/common/cpu_time.h"
#include "rvlio/common/parallel.h"
#include "rvlio/imu/noise.h"
#include "rvlio/map/output_map.h"
#include "rvlio/refine/association.h"
#include "rvlio/refine/chunks.h"
#include "rvlio/refine/init.h"
#include "rvlio/refine/problem.h"

namespace rvlio {
namespace {

using Clock = std::chrono::steady_clock;

constexpr double kConvergedTranslationM = 5e-4;  // rounds stop below both changes
constexpr double kConvergedRotationDeg = 5e-3;

// Refined scan `scan_index`'s deskewed points at T_world_lidar into the
// output map, each with its return's attributes.
void InsertRefinedScan(const RefineScanPoints& points, const Pose3& T_world_lidar,
                       const std::vector<Eigen::Vector3d>& p_lidar_end, uint32_t scan_index,
                       OutputMap* output) {
  const MapAttributeSet given{!points.intensity.empty(), true, !points.ring.empty(), true};
  MapPointAttributes a;
  a.scan_index = scan_index;
  for (size_t i = 0; i < p_lidar_end.size(); ++i) {
    if (given.intensity) a.intensity = points.intensity[i];
    if (given.ring) a.ring = points.ring[i];
    a.t_ns = points.t_ns[i];
    output->InsertPoint(T_world_lidar * p_lidar_end[i], a, given);
  }
}

// The rounds over one sequence: owns the states and the round's map; each
// step is a function of refine_*.h.
class BatchRefiner {
 public:
  BatchRefiner(const RefineConfig& config, RefineInput input)
      : config_(config),
        input_(std::move(input)),
        noise_(ImuNoise::FromOptions(config.imu)),
        solver_(RefineSolver::Make(ResolveThreads(config.refine.threads))),
        round_map_(config.map) {
    result_.linear_solver = solver_.name;
    result_.threads = solver_.threads;
  }

  StatusOr<RefineResult> Run(const RefineHooks& hooks);

 private:
  Status Initialize();
  Status Resume(const RefineRoundState& state);
  RefineRoundState State() const;
  bool StopRequested() const { return stop_ && stop_(); }
  bool RunRound(int round, RefineRound* report);
  void SolveChunk(const ScanRange& chunk, int next_begin, RefineRound* report);
  void Finish();

  const RefineConfig& config_;
  RefineInput input_;
  ImuNoise noise_;
  RefineSolver solver_;
  PoseManifold pose_manifold_;
  RefineSequence sequence_;
  std::vector<RefineState> states_;  // per refined scan
  std::vector<PoseBlock> anchors_;   // per refined scan: its initial pose (degeneracy priors)
  RefineRoundMap round_map_;
  std::function<bool()> stop_;  // RefineHooks::stop
  RefineResult result_;
};

// Scans, gravity and the initial states (the scans' stamps; a resumed state
// replaces the rest).
Status BatchRefiner::Initialize() {
  if (Status s = CheckRefineInput(input_); !s.ok()) return s;
  StatusOr<RefineSequence> sequence = SelectRefineScans(input_, &result_.stats);
  if (!sequence.ok()) return sequence.status();
  sequence_ = std::move(sequence).value();
  ReleaseInputPoints(&input_);  // sequence_ holds the refined scans' points
  const RefineGravity g = InitRefineGravity(input_.imu, input_.init, config_.imu);
  result_.g_world = g.g_world;
  result_.stats.started_moving = g.started_moving;
  result_.stats.gravity_from_static = g.from_static;
  if (!g.warning.empty()) result_.warnings.push_back(g.warning);
  states_ = InitialRefineStates(sequence_, input_.init, g.bg);
  anchors_.reserve(states_.size());
  for (const RefineState& s : states_) anchors_.push_back(PoseBlock::FromArray(s.pose.data()));
  return Status::Ok();
}

// next_begin: the next chunk's first scan (the scan count after the last).
void BatchRefiner::SolveChunk(const ScanRange& chunk, int next_begin, RefineRound* report) {
  auto t0 = Clock::now();
  ChunkAssociation a =
      AssociateRefineChunk(config_, round_map_, states_, chunk, solver_.threads, stop_);
  report->points += a.points;
  report->constraints += a.constraints;
  report->rv_active_scans += a.rv_active_scans;
  report->degenerate_scans += a.degenerate_scans;
  report->associate_s += SecondsSince(t0);
  if (StopRequested()) return;
  ReleaseAssociatedScans(chunk, next_begin, &round_map_);

  t0 = Clock::now();
  ceres::Problem problem(RefineProblemOptions());
  const bool gauge_fixed =
      config_.reference != nullptr || RangeHoldsTie(config_.survey.ties, chunk, states_);
  const bool hold_first_pose = chunk.begin > 0 || !gauge_fixed;
  BuildRefineChunkProblem(sequence_, noise_, result_.g_world, chunk, hold_first_pose, &a.factors,
                          &pose_manifold_, &states_, &problem);
  AddRefineDegeneracyPriors(chunk, a.factors, anchors_, &states_, &problem);
  AddRefinePositionTies(config_.survey.ties, chunk, &states_, &problem);
  if (config_.survey.rest_sigma_v > 0.0)
    AddRefineRestFactors(config_.survey.rests, config_.survey.rest_sigma_v, chunk, &states_,
                         &problem);
  const RefineSolveReport r = SolveRefineProblem(
      &problem, solver_.Options(config_.refine.solver_iterations), chunk, stop_, &states_);
  if (!r.accepted) {
    ++report->solve_failures;
    result_.warnings.push_back("round " + std::to_string(report->round) + ": the solve of scans " +
                               std::to_string(chunk.begin) + ".." + std::to_string(chunk.end - 1) +
                               " failed (" + r.message + "); kept the previous estimate");
  } else {
    report->cost_before += r.cost_before;
    report->cost_after += r.cost_after;
  }
  report->iterations += r.iterations;
  report->solve_s += SecondsSince(t0);
}

// False (states and warnings as before the round) when a stop was requested.
bool BatchRefiner::RunRound(int round, RefineRound* out) {
  const auto t_round = Clock::now();
  RefineRound report;
  report.round = round;
  const std::vector<RefineState> start = states_;
  const size_t warnings_before = result_.warnings.size();
  const RefineStats stats_before = result_.stats;
  auto stopped = [&] {
    if (!StopRequested()) return false;
    states_ = start;
    result_.warnings.resize(warnings_before);
    result_.stats = stats_before;
    return true;
  };
  auto t0 = Clock::now();
  DeskewRefineScans(sequence_, states_, result_.g_world, config_.T_imu_lidar, solver_.threads,
                    &round_map_.p_lidar_end);
  report.deskew_s = SecondsSince(t0);
  if (stopped()) return false;
  t0 = Clock::now();
  BuildRefineMap(states_, config_.T_imu_lidar, &round_map_);
  result_.stats.map_entries = round_map_.map.stats().entries;
  report.map_s = SecondsSince(t0);
  if (stopped()) return false;
  const std::vector<ScanRange> chunks =
      MakeRefineChunks(sequence_.size(), config_.refine.chunk_scans);
  report.chunks = static_cast<int>(chunks.size());
  result_.stats.chunks = report.chunks;
  for (size_t c = 0; c < chunks.size(); ++c) {
    SolveChunk(chunks[c], c + 1 < chunks.size() ? chunks[c + 1].begin : sequence_.size(), &report);
    if (stopped()) return false;
  }
  for (size_t k = 0; k < states_.size(); ++k) {
    const Pose3 a = start[k].T_world_imu(), b = states_[k].T_world_imu();
    report.max_translation_change_m =
        std::max(report.max_translation_change_m, TranslationDifference(a, b));
    report.max_rotation_change_deg =
        std::max(report.max_rotation_change_deg, RotationDifferenceDeg(a, b));
  }
  report.total_s = SecondsSince(t_round);
  *out = report;
  return true;
}

Status BatchRefiner::Resume(const RefineRoundState& state) {
  if (Status s = CheckResumedStates(state.states, states_); !s.ok()) return s;
  states_ = state.states;
  result_.g_world = state.g_world;
  result_.rounds = state.rounds;
  result_.warnings = state.warnings;
  result_.converged = state.converged;
  result_.init_solve_s = state.init_solve_s;
  result_.stats.map_entries = state.map_entries;
  result_.stats.chunks = state.chunks;
  return Status::Ok();
}

RefineRoundState BatchRefiner::State() const {
  RefineRoundState s;
  s.rounds_done = result_.rounds.empty() ? 0 : result_.rounds.back().round;
  s.converged = result_.converged;
  s.states = states_;
  s.g_world = result_.g_world;
  s.rounds = result_.rounds;
  s.warnings = result_.warnings;
  s.init_solve_s = result_.init_solve_s;
  s.map_entries = result_.stats.map_entries;
  s.chunks = result_.stats.chunks;
  return s;
}

// Trajectory, velocities, biases and the output map at the final estimate.
void BatchRefiner::Finish() {
  std::vector<std::vector<Eigen::Vector3d>>& p_lidar_end = round_map_.p_lidar_end;
  DeskewRefineScans(sequence_, states_, result_.g_world, config_.T_imu_lidar, solver_.threads,
                    &p_lidar_end);
  OutputMap output(config_.map.output_resolution);
  for (size_t k = 0; k < states_.size(); ++k) {
    const Pose3 T_world_imu = states_[k].T_world_imu();
    InsertRefinedScan(sequence_.points[k], T_world_imu * config_.T_imu_lidar, p_lidar_end[k],
                      static_cast<uint32_t>(k), &output);
    StampedPose sp;
    sp.t_ns = states_[k].t_ns;
    sp.p_world_imu = T_world_imu.t;
    sp.q_world_imu = T_world_imu.quaternion();
    result_.trajectory.push_back(sp);
    const SpeedBiasBlock sb = states_[k].SpeedBias();
    result_.v_world_imu.push_back(sb.v_world_imu);
    result_.gyro_bias.push_back(sb.bg);
    result_.accel_bias.push_back(sb.ba);
  }
  result_.map = output.Cloud();
}

StatusOr<RefineResult> BatchRefiner::Run(const RefineHooks& hooks) {
  const auto t0 = Clock::now();
  stop_ = hooks.stop;
  if (Status s = Initialize(); !s.ok()) return s;
  if (hooks.resume != nullptr) {
    if (Status s = Resume(*hooks.resume); !s.ok()) return s;
  } else {
    const auto t_init = Clock::now();
    const RefineSolveReport r =
        SolveVelocityAndBias(sequence_, noise_, result_.g_world, solver_, &states_);
    if (!r.accepted)
      result_.warnings.push_back("the IMU-only velocity and bias solve failed (" + r.message +
                                 "); kept finite differences and zero biases");
    result_.init_solve_s = SecondsSince(t_init);
    if (hooks.on_state)
      if (Status s = hooks.on_state(State()); !s.ok()) return s;
  }
  const int first = hooks.resume != nullptr ? hooks.resume->rounds_done + 1 : 1;
  for (int round = first; !result_.converged && round <= config_.refine.rounds; ++round) {
    RefineRound r;
    if (StopRequested() || !RunRound(round, &r)) {
      result_.stopped = true;
      break;
    }
    result_.rounds.push_back(r);
    if (hooks.on_round) hooks.on_round(r);
    result_.converged = r.max_translation_change_m < kConvergedTranslationM &&
                        r.max_rotation_change_deg < kConvergedRotationDeg;
    if (hooks.on_state)
      if (Status s = hooks.on_state(State()); !s.ok()) return s;
  }
  Finish();
  result_.total_s = SecondsSince(t0);
  return std::move(result_);
}

}  // namespace

StatusOr<RefineResult> Refine(const RefineConfig& config, RefineInput input,
                              const RefineRoundCallback& on_round) {
  RefineHooks hooks;
  hooks.on_round = on_round;
  return Refine(config, std::move(input), hooks);
}

StatusOr<RefineResult> Refine(const RefineConfig& config, RefineInput input,
                              const RefineHooks& hooks) {
  RefineConfig checked = config;
  for (Status s : {checked.imu.Validate(), checked.map.Validate(), checked.constraints.Validate(),
                   checked.rv.Validate(), checked.degeneracy.Validate(), checked.refine.Validate()})
    if (!s.ok()) return s;
  BatchRefiner refiner(config, std::move(input));
  return refiner.Run(hooks);
}

}  // namespace rvlio

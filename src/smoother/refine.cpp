// Batch refinement: Deskew -> Map -> Associate -> RV -> Solve, a few rounds
// (see refine.h).
#include "rvlio/smoother/refine.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <thread>
#include <utility>

#include <ceres/iteration_callback.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <ceres/types.h>

#include "rvlio/common/check.h"
#include "rvlio/constraints/robust_kernel.h"
#include "rvlio/imu/noise.h"
#include "rvlio/imu/preintegration.h"
#include "rvlio/imu/static_init.h"
#include "rvlio/map/output_map.h"
#include "rvlio/rv/rv.h"
#include "rvlio/smoother/imu_factor.h"
#include "rvlio/smoother/manifolds.h"
#include "rvlio/smoother/plane_factor.h"
#include "rvlio/smoother/refine_map.h"
#include "rvlio/smoother/refine_pair_factor.h"
#include "rvlio/smoother/refine_states.h"

namespace rvlio {
namespace {

using Clock = std::chrono::steady_clock;

constexpr TimeNs kVelocityHalfWindowNs = 50000000;  // 50 ms central differences
constexpr double kConvergedTranslationM = 5e-4;     // rounds stop below both changes
constexpr double kConvergedRotationDeg = 5e-3;
constexpr double kChunkOverlap = 0.1;               // fraction of refine_chunk_scans

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string Seconds(TimeNs t_ns) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3f", NsToSeconds(t_ns));
  return buf;
}

// fn(i, thread) for i in [begin, end) on `threads` threads; each index is
// processed exactly once, so results written per index are deterministic.
template <class Fn>
void ParallelFor(int begin, int end, int threads, const Fn& fn) {
  threads = std::max(1, std::min(threads, end - begin));
  if (threads == 1) {
    for (int i = begin; i < end; ++i) fn(i, 0);
    return;
  }
  std::atomic<int> next(begin);
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      for (int i = next++; i < end; i = next++) fn(i, t);
    });
  for (auto& th : pool) th.join();
}

bool AllFinite(const RefineState& s) {
  for (double x : s.pose) if (!std::isfinite(x)) return false;
  for (double x : s.speed_bias) if (!std::isfinite(x)) return false;
  return true;
}

// [begin, end) scan ranges: chunk_scans long, each starting `overlap` scans
// before the previous one ends.
std::vector<std::pair<int, int>> MakeChunks(int n, int chunk_scans) {
  const int overlap = std::max(2, static_cast<int>(std::lround(kChunkOverlap * chunk_scans)));
  std::vector<std::pair<int, int>> chunks;
  for (int begin = 0;;) {
    const int end = std::min(n, begin + chunk_scans);
    chunks.emplace_back(begin, end);
    if (end == n) break;
    begin = end - overlap;
  }
  return chunks;
}

// The plane factors of one scan: world-fixed planes, and planes attached to
// their source scans (refine_pair_factor.h).
struct ScanFactors {
  std::unique_ptr<PlaneFactor> fixed;
  std::vector<std::pair<int, std::unique_ptr<ScanPairPlaneFactor>>> pairs;  // source scan, factor
};

// Per-thread scratch of association.
struct AssociationWorkspace {
  ConstraintList list, fixed;
  std::vector<int32_t> sources;
  std::vector<std::pair<int32_t, int>> attached;  // source scan, constraint index
  RvWorkspace rv;
};

class BatchRefiner {
 public:
  BatchRefiner(const RefineConfig& config, RefineInput input)
      : config_(config),
        input_(std::move(input)),
        noise_(ImuNoise::FromOptions(config.imu)),
        map_(config.map) {
    threads_ = config.smoother.refine_threads > 0
                   ? config.smoother.refine_threads
                   : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
    const bool suitesparse =
        ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE);
    sparse_library_ = suitesparse ? ceres::SUITE_SPARSE : ceres::EIGEN_SPARSE;
    result_.linear_solver = suitesparse ? "SPARSE_NORMAL_CHOLESKY (SuiteSparse CHOLMOD)"
                                        : "SPARSE_NORMAL_CHOLESKY (Eigen sparse)";
    result_.threads = threads_;
  }

  StatusOr<RefineResult> Run(const RefineHooks& hooks);

 private:
  Status SelectScans();
  Status CheckInput() const;
  void InitGravity();
  void InitStates();
  void SolveVelocityAndBias();
  Status Resume(const RefineRoundState& state);
  RefineRoundState State() const;
  bool StopRequested() const { return stop_ && stop_(); }
  bool RunRound(int round, RefineRound* report);
  void DeskewAll();
  void BuildMap();
  void SolveChunk(int begin, int end, RefineRound* report);
  ScanFactors AssociateOne(int k, int begin, int end, AssociationWorkspace* w,
                           AssociationStats* stats, bool* rv_active) const;
  ScanFactors SplitFactors(int k, int begin, int end, AssociationWorkspace* w) const;
  void AddImuFactors(int begin, int end, ceres::Problem* problem);
  ceres::Solver::Options SolverOptions(int iterations) const;
  void Finish();

  const RefineConfig& config_;
  RefineInput input_;
  ImuNoise noise_;
  RefineMap map_;
  PoseManifold pose_manifold_;
  int threads_ = 1;
  ceres::SparseLinearAlgebraLibraryType sparse_library_;
  Eigen::Vector3d bg0_ = Eigen::Vector3d::Zero();

  std::vector<int> kept_;                          // input scan index per refined scan
  std::vector<RefineState> states_;                // per refined scan
  std::vector<std::vector<Eigen::Vector3d>> p_lidar_end_;  // deskewed, per refined scan
  std::vector<Pose3> map_poses_;  // T_world_imu of each scan when the map was built
  std::function<bool()> stop_;    // RefineHooks::stop
  RefineResult result_;
};

// Ends a Ceres solve when the refinement is asked to stop (the round is
// dropped then, so the partial solve is never used).
class StopCallback : public ceres::IterationCallback {
 public:
  explicit StopCallback(const std::function<bool()>& stop) : stop_(stop) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return stop_ && stop_() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  const std::function<bool()>& stop_;
};

Status BatchRefiner::CheckInput() const {
  if (input_.init.empty()) return Status::InvalidInput("the initial trajectory has no poses");
  if (input_.imu.empty()) return Status::InvalidInput("no IMU samples to refine with");
  if (input_.scans.empty()) return Status::InvalidInput("no scans to refine");
  return Status::Ok();
}

// Keeps the scans with enough points, inside the initial trajectory's span,
// covered by IMU data and with increasing end times.
Status BatchRefiner::SelectScans() {
  RefineStats& st = result_.stats;
  st.scans_input = static_cast<int64_t>(input_.scans.size());
  st.imu_samples = static_cast<int64_t>(input_.imu.size());
  const TimeNs init0 = input_.init.front().t_ns, init1 = input_.init.back().t_ns;
  const TimeNs imu0 = input_.imu.front().t_ns, imu1 = input_.imu.back().t_ns;
  for (size_t i = 0; i < input_.scans.size(); ++i) {
    const Scan& s = input_.scans[i];
    if (static_cast<int>(s.points.size()) < kRefineMinScanPoints) {
      ++st.scans_too_few_points;
    } else if (s.t_end_ns < init0 || s.t_end_ns > init1) {
      ++st.scans_outside_init;
    } else if (s.t_start_ns < imu0 || s.t_end_ns > imu1) {
      ++st.scans_without_imu;
    } else if (!kept_.empty() && s.t_end_ns <= input_.scans[kept_.back()].t_end_ns) {
      ++st.scans_out_of_order;
    } else {
      kept_.push_back(static_cast<int>(i));
    }
  }
  st.scans_refined = static_cast<int64_t>(kept_.size());
  if (kept_.size() >= 2) return Status::Ok();
  const TimeNs scan0 = input_.scans.front().t_end_ns, scan1 = input_.scans.back().t_end_ns;
  std::string why = "only " + std::to_string(kept_.size()) + " of " +
                    std::to_string(st.scans_input) + " scans can be refined (need 2): ";
  if (init1 < scan0 || init0 > scan1)
    return Status::InvalidInput(why + "the initial trajectory (" + Seconds(init0) + " .. " +
                                Seconds(init1) + " s) does not overlap the scans (" +
                                Seconds(scan0) + " .. " + Seconds(scan1) + " s)");
  return Status::InvalidInput(
      why + std::to_string(st.scans_outside_init) + " outside the initial trajectory (" +
      Seconds(init0) + " .. " + Seconds(init1) + " s), " + std::to_string(st.scans_without_imu) +
      " without IMU coverage (" + Seconds(imu0) + " .. " + Seconds(imu1) + " s), " +
      std::to_string(st.scans_too_few_points) + " with fewer than " +
      std::to_string(kRefineMinScanPoints) + " points");
}

// Static alignment of the first imu.init_duration of samples, carried into
// the initial trajectory's world frame by its attitude there (refine.h).
void BatchRefiner::InitGravity() {
  const TimeNs t0 = input_.imu.front().t_ns;
  const TimeNs t1 = t0 + SecondsToNs(config_.imu.init_duration);
  std::vector<ImuSample> first;
  for (const ImuSample& s : input_.imu) {
    if (s.t_ns > t1) break;
    first.push_back(s);
  }
  const StaticAlignment a = AlignStatic(first);
  result_.stats.started_moving = a.moving;
  if (a.moving) {
    result_.g_world = Eigen::Vector3d(0.0, 0.0, -config_.imu.gravity);
    result_.warnings.push_back(
        "the sequence starts moving: gravity taken as (0, 0, -imu.gravity) in the initial "
        "trajectory's frame (assumed gravity-aligned, z up) and gyro bias starting at zero");
    return;
  }
  const TimeNs t_mid = std::clamp(first.front().t_ns + (first.back().t_ns - first.front().t_ns) / 2,
                                  input_.init.front().t_ns, input_.init.back().t_ns);
  Pose3 T;
  InterpolatePose(input_.init, t_mid, &T);
  const Eigen::Vector3d g_imu = a.R_world_imu.transpose() * a.g_world;
  result_.g_world = T.R * g_imu;
  result_.stats.gravity_from_static = true;
  bg0_ = a.gyro_bias;
}

void BatchRefiner::InitStates() {
  states_.resize(kept_.size());
  for (size_t k = 0; k < kept_.size(); ++k) {
    RefineState& s = states_[k];
    s.t_ns = input_.scans[kept_[k]].t_end_ns;
    Pose3 T;
    InterpolatePose(input_.init, s.t_ns, &T);
    PoseBlock(T).ToArray(s.pose.data());
    SpeedBiasBlock sb;
    sb.v_world_imu = FiniteDifferenceVelocity(input_.init, s.t_ns, kVelocityHalfWindowNs);
    sb.bg = bg0_;
    sb.ToArray(s.speed_bias.data());
  }
}

void BatchRefiner::AddImuFactors(int begin, int end, ceres::Problem* problem) {
  for (int k = begin + 1; k < end; ++k) {
    RefineState& a = states_[k - 1];
    RefineState& b = states_[k];
    const SpeedBiasBlock sb = a.SpeedBias();
    auto pre = ImuPreintegration::FromSamples(SliceImu(input_.imu, a.t_ns, b.t_ns), a.t_ns,
                                              b.t_ns, noise_, sb.bg, sb.ba);
    problem->AddResidualBlock(new ImuFactor(std::move(pre), result_.g_world), nullptr,
                              {a.pose.data(), a.speed_bias.data(), b.pose.data(),
                               b.speed_bias.data()});
  }
}

ceres::Solver::Options BatchRefiner::SolverOptions(int iterations) const {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  o.sparse_linear_algebra_library_type = sparse_library_;
  o.max_num_iterations = iterations;
  o.num_threads = threads_;
  o.logging_type = ceres::SILENT;
  o.minimizer_progress_to_stdout = false;
  return o;
}

ceres::Problem::Options ProblemOptions() {
  ceres::Problem::Options o;
  o.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // one shared PoseManifold
  return o;
}

// Velocities and biases consistent with the IMU and the initial poses: an
// IMU-only solve with every pose held.
void BatchRefiner::SolveVelocityAndBias() {
  const auto t0 = Clock::now();
  const std::vector<RefineState> before = states_;
  ceres::Problem problem(ProblemOptions());
  for (RefineState& s : states_) {
    problem.AddParameterBlock(s.pose.data(), 7, &pose_manifold_);
    problem.SetParameterBlockConstant(s.pose.data());
    problem.AddParameterBlock(s.speed_bias.data(), 9);
  }
  AddImuFactors(0, static_cast<int>(states_.size()), &problem);
  ceres::Solver::Summary summary;
  ceres::Solve(SolverOptions(20), &problem, &summary);
  if (!summary.IsSolutionUsable() || !std::all_of(states_.begin(), states_.end(), AllFinite)) {
    states_ = before;
    result_.warnings.push_back("the IMU-only velocity and bias solve failed (" +
                               summary.message + "); kept finite differences and zero biases");
  }
  result_.init_solve_s = SecondsSince(t0);
}

void BatchRefiner::DeskewAll() {
  p_lidar_end_.resize(states_.size());
  ParallelFor(0, static_cast<int>(states_.size()), threads_, [&](int k, int) {
    const Scan& scan = input_.scans[kept_[k]];
    DeskewWithImu(SliceImu(input_.imu, scan.t_start_ns, scan.t_end_ns), states_[k],
                  result_.g_world, config_.T_imu_lidar, scan.points, scan.t_start_ns,
                  &p_lidar_end_[k]);
  });
}

void BatchRefiner::BuildMap() {
  map_.Clear();
  map_poses_.resize(states_.size());
  std::vector<Eigen::Vector3d> p_world;
  for (size_t k = 0; k < states_.size(); ++k) {
    map_poses_[k] = states_[k].T_world_imu();
    const Pose3 T_world_lidar = map_poses_[k] * config_.T_imu_lidar;
    p_world.resize(p_lidar_end_[k].size());
    for (size_t i = 0; i < p_world.size(); ++i) p_world[i] = T_world_lidar * p_lidar_end_[k][i];
    map_.Insert(static_cast<int32_t>(k), p_world);
  }
  result_.stats.map_entries = map_.stats().entries;
}

// Associate -> RV -> Huber weights -> the scan's plane factors.
ScanFactors BatchRefiner::AssociateOne(int k, int begin, int end, AssociationWorkspace* w,
                                       AssociationStats* stats, bool* rv_active) const {
  const Pose3 T_world_lidar = states_[k].T_world_imu() * config_.T_imu_lidar;
  AssociateScan(p_lidar_end_[k], T_world_lidar, k, map_, config_.constraints, &w->list, stats,
                &w->sources);
  *rv_active = false;
  if (w->list.empty()) return ScanFactors();
  *rv_active = ApplyRv(config_.rv, T_world_lidar, &w->list, &w->rv).active;
  // Huber weights at the association estimate (constraints/robust_kernel.h).
  ApplyHuberWeights(config_.smoother.refine_huber_delta, &w->list);
  return SplitFactors(k, begin, end, w);
}

// A plane whose source scan j is in the chunk and within refine_plane_window
// scans of k moves with j (expressed in j's IMU frame at the map's pose);
// any other plane is world-fixed, at the current estimate of its source (a
// source in an earlier chunk has already moved in this round).
ScanFactors BatchRefiner::SplitFactors(int k, int begin, int end,
                                       AssociationWorkspace* w) const {
  const int window = config_.smoother.refine_plane_window;
  const double sigma = config_.constraints.lidar_noise;
  w->fixed.clear();
  w->attached.clear();
  for (size_t i = 0; i < w->list.size(); ++i) {
    const int j = w->sources[i];
    if (window > 0 && j >= begin && j < end && std::abs(j - k) <= window) {
      w->attached.emplace_back(j, static_cast<int>(i));
      continue;
    }
    Constraint c = w->list[i];
    if (j < begin) {  // T_j,now T_j,map^-1 carries the plane along
      const Pose3 moved = states_[j].T_world_imu() * map_poses_[j].Inverse();
      c.normal_world = moved.R * c.normal_world;
      c.q_world = moved * c.q_world;
    }
    w->fixed.push_back(c);
  }
  ScanFactors f;
  if (!w->fixed.empty())
    f.fixed = std::make_unique<PlaneFactor>(w->fixed, config_.T_imu_lidar, sigma);
  std::sort(w->attached.begin(), w->attached.end());
  for (size_t a = 0; a < w->attached.size(); ++a) {
    const int j = w->attached[a].first;
    if (a == 0 || w->attached[a - 1].first != j)
      f.pairs.emplace_back(j, std::make_unique<ScanPairPlaneFactor>());
    const Constraint& c = w->list[w->attached[a].second];
    const Pose3& T_j = map_poses_[j];
    f.pairs.back().second->Add(config_.T_imu_lidar * c.p_lidar, T_j.R.transpose() * c.normal_world,
                               T_j.Inverse() * c.q_world, c.weight, sigma);
  }
  for (auto& [j, pair] : f.pairs) pair->Finalize();
  return f;
}

void BatchRefiner::SolveChunk(int begin, int end, RefineRound* report) {
  // Associate the chunk's scans (threads over scans, one workspace each).
  auto t0 = Clock::now();
  const int n = end - begin;
  std::vector<ScanFactors> factors(n);
  std::vector<AssociationStats> stats(n);
  std::vector<char> active(n, 0);
  std::vector<AssociationWorkspace> workspaces(threads_);
  ParallelFor(begin, end, threads_, [&](int k, int t) {
    if (StopRequested()) return;  // the round is dropped
    bool a = false;
    factors[k - begin] = AssociateOne(k, begin, end, &workspaces[t], &stats[k - begin], &a);
    active[k - begin] = a;
  });
  for (int i = 0; i < n; ++i) {
    report->points += stats[i].num_points;
    report->constraints += stats[i].num_accepted;
    report->rv_active_scans += active[i];
  }
  report->associate_s += SecondsSince(t0);
  if (StopRequested()) return;

  // One problem: PlaneFactor per scan, ImuFactor between consecutive scans.
  t0 = Clock::now();
  ceres::Problem problem(ProblemOptions());
  for (int k = begin; k < end; ++k) {
    problem.AddParameterBlock(states_[k].pose.data(), 7, &pose_manifold_);
    problem.AddParameterBlock(states_[k].speed_bias.data(), 9);
  }
  for (int k = begin; k < end; ++k) {
    ScanFactors& f = factors[k - begin];
    if (f.fixed) problem.AddResidualBlock(f.fixed.release(), nullptr, states_[k].pose.data());
    for (auto& [j, pair] : f.pairs)
      problem.AddResidualBlock(pair.release(), nullptr, states_[k].pose.data(),
                               states_[j].pose.data());
  }
  AddImuFactors(begin, end, &problem);
  problem.SetParameterBlockConstant(states_[begin].pose.data());  // gauge / previous chunk
  const std::vector<RefineState> before(states_.begin() + begin, states_.begin() + end);
  ceres::Solver::Summary summary;
  ceres::Solver::Options options = SolverOptions(config_.smoother.refine_solver_iterations);
  StopCallback stop(stop_);
  options.callbacks.push_back(&stop);
  ceres::Solve(options, &problem, &summary);
  const bool finite = std::all_of(states_.begin() + begin, states_.begin() + end, AllFinite);
  if (!summary.IsSolutionUsable() || !finite || !std::isfinite(summary.final_cost)) {
    std::copy(before.begin(), before.end(), states_.begin() + begin);
    ++report->solve_failures;
    result_.warnings.push_back("round " + std::to_string(report->round) + ": the solve of scans " +
                               std::to_string(begin) + ".." + std::to_string(end - 1) +
                               " failed (" + summary.message + "); kept the previous estimate");
  } else {
    report->cost_before += summary.initial_cost;
    report->cost_after += summary.final_cost;
  }
  report->iterations += static_cast<int>(summary.iterations.size()) - 1;
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
  DeskewAll();
  report.deskew_s = SecondsSince(t0);
  if (stopped()) return false;
  t0 = Clock::now();
  BuildMap();
  report.map_s = SecondsSince(t0);
  if (stopped()) return false;
  const auto chunks = MakeChunks(static_cast<int>(states_.size()),
                                 config_.smoother.refine_chunk_scans);
  report.chunks = static_cast<int>(chunks.size());
  result_.stats.chunks = report.chunks;
  for (const auto& [begin, end] : chunks) {
    SolveChunk(begin, end, &report);
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
  if (state.states.size() != states_.size())
    return Status::InvalidInput("the resumed state has " + std::to_string(state.states.size()) +
                                " scan states, this input refines " +
                                std::to_string(states_.size()) + " scans");
  for (size_t k = 0; k < states_.size(); ++k)
    if (state.states[k].t_ns != states_[k].t_ns || !AllFinite(state.states[k]))
      return Status::InvalidInput("the resumed state of scan " + std::to_string(k) +
                                  " does not belong to this input (stamp " +
                                  Seconds(state.states[k].t_ns) + " s, expected " +
                                  Seconds(states_[k].t_ns) + " s)");
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
  DeskewAll();
  OutputMap output(config_.map.output_resolution);
  std::vector<Eigen::Vector3d> p_world;
  for (size_t k = 0; k < states_.size(); ++k) {
    const Pose3 T_world_imu = states_[k].T_world_imu();
    const Pose3 T_world_lidar = T_world_imu * config_.T_imu_lidar;
    p_world.resize(p_lidar_end_[k].size());
    for (size_t i = 0; i < p_world.size(); ++i) p_world[i] = T_world_lidar * p_lidar_end_[k][i];
    output.Insert(p_world);
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
  result_.map_points = output.Points();
}

StatusOr<RefineResult> BatchRefiner::Run(const RefineHooks& hooks) {
  const auto t0 = Clock::now();
  stop_ = hooks.stop;
  if (Status s = CheckInput(); !s.ok()) return s;
  if (Status s = SelectScans(); !s.ok()) return s;
  InitGravity();
  InitStates();  // the scans' stamps; a resumed state replaces the rest
  if (hooks.resume != nullptr) {
    if (Status s = Resume(*hooks.resume); !s.ok()) return s;
  } else {
    SolveVelocityAndBias();
    if (hooks.on_state)
      if (Status s = hooks.on_state(State()); !s.ok()) return s;
  }
  const int first = hooks.resume != nullptr ? hooks.resume->rounds_done + 1 : 1;
  for (int round = first; !result_.converged && round <= config_.smoother.refine_rounds; ++round) {
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
                   checked.rv.Validate(), checked.smoother.Validate()})
    if (!s.ok()) return s;
  BatchRefiner refiner(config, std::move(input));
  return refiner.Run(hooks);
}

}  // namespace rvlio

#include "rvlio/refine/problem.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <ceres/iteration_callback.h>

#include "rvlio/imu/preintegration.h"
#include "rvlio/factors/imu_factor.h"
#include "rvlio/factors/pose_projected_factor.h"
#include "rvlio/factors/prior_factor.h"

namespace rvlio {
namespace {

constexpr int kVelocityBiasIterations = 20;  // the IMU-only solve converges in a few

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

// The weak directions of scan k (pose tangent of k: body-frame rotation,
// world translation) as directions of pose j's tangent: the same world
// rotation axes in j's body frame, the same world translations.
PoseProjectedFactor::Directions TransportedDirections(const PoseProjectedFactor::Directions& held_k,
                                                      const PoseBlock& pose_k,
                                                      const PoseBlock& pose_j) {
  PoseProjectedFactor::Directions held_j = held_k;
  const Eigen::Matrix3d R_j_k =
      (pose_j.q_world_imu.conjugate() * pose_k.q_world_imu).toRotationMatrix();
  held_j.middleRows<3>(PoseBlock::kRot) = R_j_k * held_k.middleRows<3>(PoseBlock::kRot);
  return held_j;
}

// The cost of one of scan k's factors (pose_k its first block; a pair's
// second block is pose_j, the scan whose planes it uses): the factor itself,
// handed to the problem; or, remap in the project form, a PoseProjectedFactor
// around it, which stays with f. The poses are projected at their estimates
// of the association (the chunk's states are not solved yet); a pair factor
// in both poses, so the scan's constraints say nothing along its weak
// directions, neither about its own pose nor about the scans that hold its
// planes.
ceres::CostFunction* ScanCost(const ScanFactors& f, std::unique_ptr<ceres::CostFunction>* factor,
                              const RefineState& scan, const RefineState* source = nullptr) {
  if (f.remap_held.cols() == 0) return factor->release();
  const PoseBlock pose_k = PoseBlock::FromArray(scan.pose.data());
  if (source == nullptr) return new PoseProjectedFactor(factor->get(), pose_k, f.remap_held);
  const PoseBlock pose_j = PoseBlock::FromArray(source->pose.data());
  return new PoseProjectedFactor(
      factor->get(), {{0, pose_k, f.remap_held},
                      {1, pose_j, TransportedDirections(f.remap_held, pose_k, pose_j)}});
}

}  // namespace

ceres::Problem::Options RefineProblemOptions() {
  ceres::Problem::Options o;
  o.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // one shared PoseManifold
  return o;
}

void AddRefineStateBlocks(const ScanRange& range, bool hold_poses, PoseManifold* pose_manifold,
                          std::vector<RefineState>* states, ceres::Problem* problem) {
  for (int k = range.begin; k < range.end; ++k) {
    RefineState& s = (*states)[k];
    problem->AddParameterBlock(s.pose.data(), 7, pose_manifold);
    if (hold_poses) problem->SetParameterBlockConstant(s.pose.data());
    problem->AddParameterBlock(s.speed_bias.data(), 9);
  }
}

void AddRefineImuFactors(const RefineSequence& sequence, const ImuNoise& noise,
                         const Eigen::Vector3d& g_world, const ScanRange& range,
                         std::vector<RefineState>* states, ceres::Problem* problem) {
  for (int k = range.begin + 1; k < range.end; ++k) {
    RefineState& a = (*states)[k - 1];
    RefineState& b = (*states)[k];
    const SpeedBiasBlock sb = a.SpeedBias();
    auto pre = ImuPreintegration::FromSamples(SliceImu(sequence.imu(), a.t_ns, b.t_ns), a.t_ns,
                                              b.t_ns, noise, sb.bg, sb.ba);
    problem->AddResidualBlock(
        new ImuFactor(std::move(pre), g_world), nullptr,
        {a.pose.data(), a.speed_bias.data(), b.pose.data(), b.speed_bias.data()});
  }
}

void BuildRefineChunkProblem(const RefineSequence& sequence, const ImuNoise& noise,
                             const Eigen::Vector3d& g_world, const ScanRange& chunk,
                             bool hold_first_pose, std::vector<ScanFactors>* factors,
                             PoseManifold* pose_manifold, std::vector<RefineState>* states,
                             ceres::Problem* problem) {
  AddRefineStateBlocks(chunk, false, pose_manifold, states, problem);
  for (int k = chunk.begin; k < chunk.end; ++k) {
    ScanFactors& f = (*factors)[k - chunk.begin];
    double* pose_k = (*states)[k].pose.data();
    const RefineState& scan = (*states)[k];
    if (f.fixed) problem->AddResidualBlock(ScanCost(f, &f.fixed, scan), nullptr, pose_k);
    for (auto& [j, pair] : f.pairs)
      problem->AddResidualBlock(ScanCost(f, &pair, scan, &(*states)[j]), nullptr, pose_k,
                                (*states)[j].pose.data());
  }
  AddRefineImuFactors(sequence, noise, g_world, chunk, states, problem);
  if (hold_first_pose)  // gauge / previous chunk
    problem->SetParameterBlockConstant((*states)[chunk.begin].pose.data());
}

void AddRefineDegeneracyPriors(const ScanRange& chunk, const std::vector<ScanFactors>& factors,
                               const std::vector<PoseBlock>& anchors,
                               std::vector<RefineState>* states, ceres::Problem* problem) {
  for (int k = chunk.begin; k < chunk.end; ++k) {
    const ScanFactors& f = factors[k - chunk.begin];
    if (!f.has_degeneracy_prior) continue;
    problem->AddResidualBlock(new PosePriorFactor(anchors[k], f.degeneracy_sqrt_information),
                              nullptr, (*states)[k].pose.data());
  }
}

RefineSolver RefineSolver::Make(int threads) {
  RefineSolver s;
  const bool suitesparse = ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE);
  s.sparse_library = suitesparse ? ceres::SUITE_SPARSE : ceres::EIGEN_SPARSE;
  s.name = suitesparse ? "SPARSE_NORMAL_CHOLESKY (SuiteSparse CHOLMOD)"
                       : "SPARSE_NORMAL_CHOLESKY (Eigen sparse)";
  s.threads = threads;
  return s;
}

ceres::Solver::Options RefineSolver::Options(int iterations) const {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  o.sparse_linear_algebra_library_type = sparse_library;
  o.max_num_iterations = iterations;
  o.num_threads = threads;
  o.logging_type = ceres::SILENT;
  o.minimizer_progress_to_stdout = false;
  return o;
}

RefineSolveReport SolveRefineProblem(ceres::Problem* problem, ceres::Solver::Options options,
                                     const ScanRange& range, const std::function<bool()>& stop,
                                     std::vector<RefineState>* states) {
  const std::vector<RefineState> before(states->begin() + range.begin, states->begin() + range.end);
  StopCallback stop_callback(stop);
  if (stop) options.callbacks.push_back(&stop_callback);
  ceres::Solver::Summary summary;
  ceres::Solve(options, problem, &summary);
  RefineSolveReport r;
  r.message = summary.message;
  r.iterations = static_cast<int>(summary.iterations.size()) - 1;
  const bool finite =
      std::all_of(states->begin() + range.begin, states->begin() + range.end, AllFinite);
  r.accepted = summary.IsSolutionUsable() && finite && std::isfinite(summary.final_cost);
  if (!r.accepted) {
    std::copy(before.begin(), before.end(), states->begin() + range.begin);
    return r;
  }
  r.cost_before = summary.initial_cost;
  r.cost_after = summary.final_cost;
  return r;
}

RefineSolveReport SolveVelocityAndBias(const RefineSequence& sequence, const ImuNoise& noise,
                                       const Eigen::Vector3d& g_world, const RefineSolver& solver,
                                       std::vector<RefineState>* states) {
  PoseManifold pose_manifold;
  ceres::Problem problem(RefineProblemOptions());
  const ScanRange all{0, static_cast<int>(states->size())};
  AddRefineStateBlocks(all, true, &pose_manifold, states, &problem);
  AddRefineImuFactors(sequence, noise, g_world, all, states, &problem);
  return SolveRefineProblem(&problem, solver.Options(kVelocityBiasIterations), all, nullptr,
                            states);
}

}  // namespace rvlio

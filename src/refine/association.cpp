#include "rvlio/refine/association.h"

#include <algorithm>
#include <cmath>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "rvlio/common/parallel.h"
#include "rvlio/constraints/robust_kernel.h"

namespace rvlio {

void DeskewRefineScans(const RefineSequence& sequence, const std::vector<RefineState>& states,
                       const Eigen::Vector3d& g_world, const Pose3& T_imu_lidar, int threads,
                       std::vector<std::vector<Eigen::Vector3d>>* p_lidar_end) {
  p_lidar_end->resize(states.size());
  ParallelFor(0, static_cast<int>(states.size()), threads, [&](int k, int) {
    const Scan& scan = sequence.scan(k);
    const RefineScanPoints& points = sequence.points[k];
    DeskewWithImu(SliceImu(sequence.imu(), scan.t_start_ns, scan.t_end_ns), states[k], g_world,
                  T_imu_lidar, points.p_lidar, points.t_ns, scan.t_start_ns, &(*p_lidar_end)[k]);
  });
}

void BuildRefineMap(const std::vector<RefineState>& states, const Pose3& T_imu_lidar,
                    RefineRoundMap* round) {
  round->map.Clear();
  round->map_poses.resize(states.size());
  std::vector<Eigen::Vector3d> p_world;
  for (size_t k = 0; k < states.size(); ++k) {
    round->map_poses[k] = states[k].T_world_imu();
    const Pose3 T_world_lidar = round->map_poses[k] * T_imu_lidar;
    const std::vector<Eigen::Vector3d>& p_lidar = round->p_lidar_end[k];
    p_world.resize(p_lidar.size());
    for (size_t i = 0; i < p_world.size(); ++i) p_world[i] = T_world_lidar * p_lidar[i];
    round->map.Insert(static_cast<int32_t>(k), p_world);
  }
}

void ReleaseAssociatedScans(const ScanRange& chunk, int next_begin, RefineRoundMap* round) {
  std::vector<std::vector<Eigen::Vector3d>>& p = round->p_lidar_end;
  const int end = std::min(next_begin, static_cast<int>(p.size()));
  for (int k = chunk.begin; k < end; ++k) std::vector<Eigen::Vector3d>().swap(p[k]);
  if (next_begin >= static_cast<int>(p.size())) round->map.Release();
#if defined(__GLIBC__)
  // The points are freed in blocks below glibc's mmap threshold: without a
  // trim their pages stay resident while the solve allocates anew.
  malloc_trim(0);
#endif
}

void SplitScanConstraints(int k, const ScanRange& chunk, int plane_window,
                          const ConstraintList& list, const std::vector<int32_t>& sources,
                          const std::vector<RefineState>& states,
                          const std::vector<Pose3>& map_poses, ConstraintList* fixed,
                          std::vector<std::pair<int32_t, int>>* attached) {
  fixed->clear();
  attached->clear();
  for (size_t i = 0; i < list.size(); ++i) {
    const int j = sources[i];
    if (plane_window > 0 && chunk.Contains(j) && std::abs(j - k) <= plane_window) {
      attached->emplace_back(j, static_cast<int>(i));
      continue;
    }
    Constraint c = list[i];
    if (j < chunk.begin) {  // T_j,now T_j,map^-1 carries the plane along
      const Pose3 moved = states[j].T_world_imu() * map_poses[j].Inverse();
      c.normal_world = moved.R * c.normal_world;
      c.q_world = moved * c.q_world;
    }
    fixed->push_back(c);
  }
  std::sort(attached->begin(), attached->end());
}

namespace {

// Scan j's attached planes w.attached[begin, end) (expressed in the source's
// IMU frame at the map's pose) into a new factor of type Factor.
template <class Factor>
std::unique_ptr<ceres::CostFunction> MakePairFactor(const RefineAssociationWorkspace& w,
                                                    size_t begin, size_t end, const Pose3& T_j,
                                                    const Pose3& T_imu_lidar, double sigma,
                                                    std::unique_ptr<Factor> f) {
  const Pose3 T_j_inv = T_j.Inverse();
  for (size_t a = begin; a < end; ++a) {
    const Constraint& c = w.list[w.attached[a].second];
    f->Add(T_imu_lidar * c.p_lidar, T_j.R.transpose() * c.normal_world, T_j_inv * c.q_world,
           c.weight, sigma);
  }
  f->Finalize();
  return f;
}

// The factors of the split: one for the fixed planes, one per source scan of
// attached planes; summaries for groups of kRefineSummaryMinConstraints or
// more when `summarize`. center_world: scan k's position (the fixed summary's
// centre).
ScanFactors MakeScanFactors(const RefineAssociationWorkspace& w,
                            const std::vector<Pose3>& map_poses, const Pose3& T_imu_lidar,
                            double sigma, bool summarize, const Eigen::Vector3d& center_world) {
  auto summary = [&](size_t n) { return summarize && n >= kRefineSummaryMinConstraints; };
  ScanFactors f;
  if (summary(w.fixed.size()))
    f.fixed = std::make_unique<PlaneSummaryFactor>(w.fixed, T_imu_lidar, sigma, center_world);
  else if (!w.fixed.empty())
    f.fixed = std::make_unique<PlaneFactor>(w.fixed, T_imu_lidar, sigma);
  size_t sources = 0;
  for (size_t a = 0; a < w.attached.size(); ++a)
    sources += a == 0 || w.attached[a - 1].first != w.attached[a].first ? 1 : 0;
  f.pairs.reserve(sources);
  for (size_t a = 0; a < w.attached.size();) {
    const int j = w.attached[a].first;
    size_t end = a + 1;  // attached is sorted by source: j's planes
    while (end < w.attached.size() && w.attached[end].first == j) ++end;
    const size_t n = end - a;
    f.pairs.emplace_back(
        j, summary(n) ? MakePairFactor(w, a, end, map_poses[j], T_imu_lidar, sigma,
                                       std::make_unique<ScanPairSummaryFactor>())
                      : MakePairFactor(w, a, end, map_poses[j], T_imu_lidar, sigma,
                                       std::make_unique<ScanPairPlaneFactor>(static_cast<int>(n))));
    a = end;
  }
  return f;
}

// With a reference map: the scan's planes in it, world-fixed (w->reference).
void AssociateReference(const RefineConfig& config, const std::vector<Eigen::Vector3d>& p_lidar,
                        const Pose3& T_world_lidar, RefineAssociationWorkspace* w) {
  w->reference.clear();
  if (config.reference == nullptr) return;
  AssociateWith(p_lidar, T_world_lidar, *config.reference, config.constraints, &w->reference,
                nullptr);
}

// remap, localizability, regularized: the scan's weak directions at its
// current estimate, from its own and its reference planes with the weights
// before the robust kernel (the geometry, as the smoother), and the prior
// along them (degeneracy/degeneracy.h).
LeastSquaresDegeneracy AnalyzeRefineDegeneracy(const RefineConfig& config,
                                               const Pose3& T_world_imu,
                                               RefineAssociationWorkspace* w) {
  LeastSquaresDegeneracy none;
  none.report.method = config.degeneracy.method;
  if (config.degeneracy.method == DegeneracyMethod::kRv ||
      config.degeneracy.method == DegeneracyMethod::kNone)
    return none;
  const ConstraintList* all = &w->list;
  if (!w->reference.empty()) {
    w->all = w->list;
    w->all.insert(w->all.end(), w->reference.begin(), w->reference.end());
    all = &w->all;
  }
  if (static_cast<int>(all->size()) < kMinPoseConstraints) return none;
  return TreatLeastSquaresDegeneracy(config.degeneracy, *all, T_world_imu, config.T_imu_lidar,
                                     config.constraints.lidar_noise);
}

// remap in the project form (degeneracy.remap_refine_form), as in the
// smoother: the scan's factors lose their say along the weak directions and
// the IMU chain places the poses there. A chunk of one scan has no IMU factor
// to do that; it holds instead.
bool ProjectRemappedScan(const DegeneracyOptions& options, const LeastSquaresDegeneracy& d,
                         const ScanRange& chunk) {
  return options.method == DegeneracyMethod::kRemap &&
         options.remap_refine_form == RemapWindowForm::kProject && d.num_held > 0 &&
         chunk.size() > 1;
}

}  // namespace

ScanFactors AssociateRefineScan(const RefineConfig& config, const RefineRoundMap& round,
                                const std::vector<RefineState>& states, int k,
                                const ScanRange& chunk, RefineAssociationWorkspace* w,
                                AssociationStats* stats, bool* rv_active) {
  const Pose3 T_world_lidar = states[k].T_world_imu() * config.T_imu_lidar;
  AssociateScan(round.p_lidar_end[k], T_world_lidar, k, round.map, config.constraints, &w->list,
                stats, &w->sources);
  *rv_active = false;
  if (!w->list.empty()) *rv_active = ApplyRv(config.rv, T_world_lidar, &w->list, &w->rv).active;
  AssociateReference(config, round.p_lidar_end[k], T_world_lidar, w);
  const LeastSquaresDegeneracy degeneracy =
      AnalyzeRefineDegeneracy(config, states[k].T_world_imu(), w);
  // Huber weights at the association estimate (constraints/robust_kernel.h),
  // the reference planes' as the scans' own.
  ApplyHuberWeights(config.refine.huber_delta, &w->list);
  ApplyHuberWeights(config.refine.huber_delta, &w->reference);
  w->fixed.clear();
  w->attached.clear();
  if (!w->list.empty())
    SplitScanConstraints(k, chunk, config.refine.plane_window, w->list, w->sources,
                         states, round.map_poses, &w->fixed, &w->attached);
  w->fixed.insert(w->fixed.end(), w->reference.begin(), w->reference.end());
  ScanFactors f;
  if (!w->fixed.empty() || !w->attached.empty())
    f = MakeScanFactors(*w, round.map_poses, config.T_imu_lidar, config.constraints.lidar_noise,
                        config.refine.summarize_pairs, states[k].T_world_imu().t);
  f.degeneracy = degeneracy.report;
  f.has_degeneracy_prior = degeneracy.has_prior;
  f.degeneracy_sqrt_information = degeneracy.sqrt_information;
  if (ProjectRemappedScan(config.degeneracy, degeneracy, chunk)) {
    f.has_degeneracy_prior = false;
    f.remap_held = degeneracy.held_pose.leftCols(degeneracy.num_held);
  }
  return f;
}

ChunkAssociation AssociateRefineChunk(const RefineConfig& config, const RefineRoundMap& round,
                                      const std::vector<RefineState>& states,
                                      const ScanRange& chunk, int threads,
                                      const std::function<bool()>& stop) {
  const int n = chunk.size();
  ChunkAssociation out;
  out.factors.resize(n);
  std::vector<AssociationStats> stats(n);
  std::vector<char> active(n, 0);
  std::vector<RefineAssociationWorkspace> workspaces(ParallelSlots(threads, n));
  ParallelFor(chunk.begin, chunk.end, threads, [&](int k, int slot) {
    if (stop && stop()) return;  // the round is dropped
    bool a = false;
    out.factors[k - chunk.begin] = AssociateRefineScan(
        config, round, states, k, chunk, &workspaces[slot], &stats[k - chunk.begin], &a);
    active[k - chunk.begin] = a;
  });
  for (int i = 0; i < n; ++i) {
    out.points += stats[i].num_points;
    out.constraints += stats[i].num_accepted;
    out.rv_active_scans += active[i];
    out.degenerate_scans += config.degeneracy.method == DegeneracyMethod::kRv
                                ? active[i]
                                : (out.factors[i].degeneracy.degenerate ? 1 : 0);
  }
  return out;
}

}  // namespace rvlio

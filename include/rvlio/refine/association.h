#pragma once
// Batch refinement, step 2: the association round (refine/refine.h, "Each
// outer round"). Deskew every scan at its current state, build the
// leave-one-out map of all scans (refine/map.h), then per scan of a chunk:
// associate against the map, RV (rv/rv.h), Huber IRLS weights, and split the
// constraints into the scan's plane factors: planes attached to their source
// scans (ScanPairPlaneFactor) or world-fixed (PlaneFactor), the latter
// carried along with sources that an earlier chunk of the round has moved.
// Threads over scans through common/parallel.h; the result does not depend
// on the thread count.
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <ceres/cost_function.h>

#include "rvlio/constraints/constraint.h"
#include "rvlio/degeneracy/degeneracy.h"
#include "rvlio/math/pose.h"
#include "rvlio/rv/rv.h"
#include "rvlio/factors/plane_factor.h"
#include "rvlio/factors/plane_summary_factor.h"
#include "rvlio/factors/pose_projected_factor.h"
#include "rvlio/refine/refine.h"
#include "rvlio/refine/chunks.h"
#include "rvlio/refine/init.h"
#include "rvlio/refine/map.h"
#include "rvlio/refine/pair_factor.h"
#include "rvlio/refine/states.h"

namespace rvlio {

// What the scans of a round are associated against: every scan deskewed at
// its state of the round's start, and the map built from them.
struct RefineRoundMap {
  explicit RefineRoundMap(const MapOptions& options) : map(options) {}

  std::vector<std::vector<Eigen::Vector3d>>
      p_lidar_end;               // per refined scan, LiDAR frame at its end
  std::vector<Pose3> map_poses;  // T_world_imu of each scan when the map was built
  RefineMap map;
};

// Deskews every refined scan with its state (DeskewWithImu), on `threads`.
void DeskewRefineScans(const RefineSequence& sequence, const std::vector<RefineState>& states,
                       const Eigen::Vector3d& g_world, const Pose3& T_imu_lidar, int threads,
                       std::vector<std::vector<Eigen::Vector3d>>* p_lidar_end);

// Rebuilds round->map from round->p_lidar_end at `states` and records the
// poses it used in round->map_poses.
void BuildRefineMap(const std::vector<RefineState>& states, const Pose3& T_imu_lidar,
                    RefineRoundMap* round);

// Frees what no later chunk of the round reads once `chunk` is associated:
// the deskewed points of its scans before next_begin (the next chunk's first
// scan; round->p_lidar_end.size() after the last chunk) and, after the last
// chunk, the map. So a chunk's solve does not hold the points of the scans
// already associated, and the last one holds neither points nor map. The
// round's results do not change (the next round deskews and builds anew).
// With glibc, the freed pages are returned to the system (malloc_trim).
void ReleaseAssociatedScans(const ScanRange& chunk, int next_begin, RefineRoundMap* round);

// The plane factors of one scan: world-fixed planes (PlaneFactor, or
// PlaneSummaryFactor), and planes attached to their source scans
// (refine/pair_factor.h: ScanPairPlaneFactor, or ScanPairSummaryFactor), one
// factor per source. With refine.summarize_pairs a group of at
// least kRefineSummaryMinConstraints constraints becomes a summary: below,
// the summary's fixed size (~3 KB with Ceres' Jacobian) exceeds the ~190 B
// per constraint of the exact factor.
constexpr int kRefineSummaryMinConstraints = 16;

struct ScanFactors {
  std::unique_ptr<ceres::CostFunction> fixed;                                // pose_k
  std::vector<std::pair<int, std::unique_ptr<ceres::CostFunction>>> pairs;  // source j; pose_k, pose_j
  // The degeneracy stage (remap, localizability, regularized): its report,
  // and the square-root information of the prior on pose_k at its initial
  // pose, already divided by constraints.lidar_noise (has_degeneracy_prior).
  DegeneracyReport degeneracy;
  bool has_degeneracy_prior = false;
  PoseMatrix6d degeneracy_sqrt_information = PoseMatrix6d::Zero();
  // remap in the project form (degeneracy.remap_refine_form): the weak
  // directions of pose_k (columns; none: not projected); the scan's factors
  // then see the poses projected off them at the association estimate
  // (BuildRefineChunkProblem), and fixed and pairs stay here, outliving the problem.
  PoseProjectedFactor::Directions remap_held = PoseProjectedFactor::Directions(6, 0);
};

// Where the planes of scan k's constraints live. A plane whose source scan j
// (sources[i]) is in the chunk and within plane_window scans of k moves with
// j: (j, i) in *attached, sorted. Any other plane is world-fixed, at the
// current estimate of its source: a source before the chunk has already
// moved in this round, so its plane is carried by
// T_world_imu,now(j) T_world_imu,map(j)^-1. Those go to *fixed.
void SplitScanConstraints(int k, const ScanRange& chunk, int plane_window,
                          const ConstraintList& list, const std::vector<int32_t>& sources,
                          const std::vector<RefineState>& states,
                          const std::vector<Pose3>& map_poses, ConstraintList* fixed,
                          std::vector<std::pair<int32_t, int>>* attached);

// Per-slot scratch of the association.
struct RefineAssociationWorkspace {
  ConstraintList list, fixed, reference;
  ConstraintList all;  // list and reference, for the degeneracy stage with a reference map
  std::vector<int32_t> sources;
  std::vector<std::pair<int32_t, int>> attached;  // source scan, constraint index
  RvWorkspace rv;
};

// Scan k of `chunk`: associate -> RV -> Huber weights -> its plane factors
// -> the degeneracy stage on all its constraints (own and reference planes).
// *rv_active: the RV pass edited the scan's constraints.
ScanFactors AssociateRefineScan(const RefineConfig& config, const RefineRoundMap& round,
                                const std::vector<RefineState>& states, int k,
                                const ScanRange& chunk, RefineAssociationWorkspace* w,
                                AssociationStats* stats, bool* rv_active);

// The association of a chunk's scans.
struct ChunkAssociation {
  std::vector<ScanFactors> factors;  // per scan of the chunk
  int64_t points = 0;                // deskewed points tried
  int64_t constraints = 0;           // accepted
  int rv_active_scans = 0;
  int degenerate_scans = 0;  // degeneracy.method's call (rv: RV active)
};

// Every scan of the chunk, on `threads`. stop (may be empty) is polled before
// each scan; once it returns true the result is incomplete and must be
// dropped.
ChunkAssociation AssociateRefineChunk(const RefineConfig& config, const RefineRoundMap& round,
                                      const std::vector<RefineState>& states,
                                      const ScanRange& chunk, int threads,
                                      const std::function<bool()>& stop);

}  // namespace rvlio

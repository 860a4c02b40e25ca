#pragma once
// Point-to-plane association of one scan against a map (docs/design.md "The shared measurement
// model"): for each point, transform it to the world with the current estimate, take its k nearest
// map points, fit and validate a local plane (plane_fit.h) and keep the constraint when |r| <=
// max_residual.
//
// One routine serves every map: AssociateWith<Search> below, where Search is
// any type with a NeighborSearchTraits specialization (neighbor_search.h):
// the odometry's working map (VoxelMap: IESKF and sliding window) and the
// leave-one-out map of batch refinement (refine/map.h). The plane
// status mapping, normal orientation, residual gate, record filling and the
// scan loop with its statistics live only here.
// Output in point order; on several threads (AssociateWith's `threads`) the
// points are split into fixed chunks whose results are merged in point order,
// so constraints and statistics are the same for any thread count. No
// per-point heap allocation.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/check.h"
#include "rvlio/common/parallel.h"
#include "rvlio/constraints/constraint.h"
#include "rvlio/constraints/neighbor_search.h"
#include "rvlio/constraints/options.h"
#include "rvlio/constraints/plane_fit.h"
#include "rvlio/map/voxel_map.h"
#include "rvlio/math/pose.h"

namespace rvlio {

enum class AssociationOutcome : uint8_t {
  kAccepted = 0,
  kTooFewNeighbors,  // fewer than num_neighbors map points within max_neighbor_distance
  kDegenerate,       // neighbours coincide
  kLineLike,         // neighbours on a line (ring line, edge): normal undetermined
  kNotFlat,          // neighbours not on one plane (corner, clutter)
  kFarFromPlane,     // a neighbour farther than max_plane_distance from the plane
  kUncertain,        // normal too uncertain for the point noise (max_normal_std_deg)
  kLargeResidual,    // |r| > max_residual (outlier)
};

const char* ToString(AssociationOutcome outcome);

struct AssociationStats {
  int num_points = 0;  // scan points tried
  int num_accepted = 0;
  int num_too_few_neighbors = 0;
  int num_degenerate = 0;
  int num_line_like = 0;
  int num_not_flat = 0;
  int num_far_from_plane = 0;
  int num_uncertain = 0;
  int num_large_residual = 0;
  int num_reused = 0;              // points answered from an AssociationCache (no search)
  double mean_abs_residual = 0.0;  // over accepted constraints, m

  void Count(AssociationOutcome outcome);
};

// Associates one point. T_world_lidar = T_world_imu * T_imu_lidar. On
// acceptance fills *out (p_lidar, normal_world oriented towards the sensor
// origin, q_world = plane centroid, residual, weight 1, role kPlain);
// otherwise *out is unspecified. `neighbors` is scratch space.
AssociationOutcome AssociatePoint(const Eigen::Vector3d& p_lidar, const Pose3& T_world_lidar,
                                  const VoxelMap& map, const ConstraintOptions& options,
                                  NeighborBuffer* neighbors, Constraint* out);

// The local plane (or the rejection) found for each point of one scan, so
// that the later iterations of one update search the map again only for the
// points that moved more than reuse_distance (m, world) since their last
// search; the others keep their plane and get a fresh residual. (FAST-LIO2
// likewise re-searches only after an iteration converged.) The search is the
// expensive part of association (k-NN + plane fit); the reuse is ~20 ns.
// Reset() for every new scan or after the map changed. reuse_distance 0
// searches every time (the cache then only holds memory).
class AssociationCache {
 public:
  explicit AssociationCache(double reuse_distance = 0.05) : reuse_distance_(reuse_distance) {}
  void Reset() { entries_.clear(); }
  double reuse_distance() const { return reuse_distance_; }

  struct Entry {
    Eigen::Vector3d p_world = Eigen::Vector3d::Zero();  // where the point was searched
    Eigen::Vector3d normal_world = Eigen::Vector3d::UnitZ();
    Eigen::Vector3d q_world = Eigen::Vector3d::Zero();
    AssociationOutcome outcome = AssociationOutcome::kTooFewNeighbors;  // of the plane search
  };
  std::vector<Entry>& entries() { return entries_; }

 private:
  double reuse_distance_;
  std::vector<Entry> entries_;  // one per scan point, or empty
};

namespace association_detail {

AssociationOutcome FromPlaneStatus(PlaneStatus status);

// Residual test and record of one accepted plane (paper Eq. 3).
inline AssociationOutcome Accept(const Eigen::Vector3d& p_lidar, const Eigen::Vector3d& p_world,
                                 const Eigen::Vector3d& u, const Eigen::Vector3d& q,
                                 const ConstraintOptions& options, Constraint* out) {
  const double r = u.dot(p_world - q);
  if (!(std::abs(r) <= options.max_residual)) return AssociationOutcome::kLargeResidual;
  out->p_lidar = p_lidar;
  out->normal_world = u;
  out->q_world = q;
  out->residual = r;
  out->weight = 1.0;
  out->role = RvRole::kPlain;
  return AssociationOutcome::kAccepted;
}

// k-NN and plane fit: the outcome of the search (kAccepted: a valid plane,
// with its normal u oriented towards the sensor and q its centroid).
template <class Search>
[[gnu::always_inline]] inline AssociationOutcome SearchPlane(
    const Eigen::Vector3d& p_world, const Eigen::Vector3d& sensor_world, const Search& search,
    const ConstraintOptions& options, const PlaneThresholds& planes,
    typename NeighborSearchTraits<Search>::Neighbors* neighbors, Eigen::Vector3d* u,
    Eigen::Vector3d* q) {
  const int k = std::min(options.num_neighbors, kMaxNeighbors);
  if (NeighborSearchTraits<Search>::KNearest(search, p_world, k, options.max_neighbor_distance,
                                             neighbors) < k)
    return AssociationOutcome::kTooFewNeighbors;
  const LocalPlane plane = FitLocalPlane(*neighbors, planes);
  if (!plane.valid()) return FromPlaneStatus(plane.status);
  // The normal's sign is arbitrary; orient it towards the sensor so that
  // records are reproducible and readable (RV only uses |u . n_alpha|).
  *u = plane.normal;
  if (u->dot(sensor_world - plane.centroid) < 0.0) *u = -*u;
  *q = plane.centroid;
  return AssociationOutcome::kAccepted;
}

// The cache entries of a scan of n points, or null without a cache; *reuse2
// is the squared reuse distance (< 0: never reuse, as for a fresh cache).
std::vector<AssociationCache::Entry>* PrepareCache(AssociationCache* cache, size_t n,
                                                   double* reuse2);

// No per-constraint hook.
struct NoHook {
  template <class Neighbors>
  void operator()(const Neighbors&) const {}
};

// One point: its plane from the cache entry e (may be null) when the point
// moved less than sqrt(reuse2) since that search (*reused set), else from a
// search (e refreshed), then the residual test. On kAccepted *c holds the
// constraint.
// Inlined (as SearchPlane) into both loops of AssociateWith: a call per point
// cost ~5 % of the association's own instructions.
template <class Search>
[[gnu::always_inline]] inline AssociationOutcome AssociateOne(
    const Eigen::Vector3d& p_lidar, const Pose3& T_world_lidar, const Search& search,
    const ConstraintOptions& options, const PlaneThresholds& planes, AssociationCache::Entry* e,
    double reuse2, typename NeighborSearchTraits<Search>::Neighbors* neighbors, bool* reused,
    Constraint* c) {
  const Eigen::Vector3d p_world = T_world_lidar * p_lidar;
  Eigen::Vector3d u = Eigen::Vector3d::UnitZ(), q = Eigen::Vector3d::Zero();
  AssociationOutcome found;
  *reused = e != nullptr && (p_world - e->p_world).squaredNorm() < reuse2;
  if (*reused) {
    found = e->outcome;
    u = e->normal_world;
    q = e->q_world;
  } else {
    found = SearchPlane(p_world, T_world_lidar.t, search, options, planes, neighbors, &u, &q);
    if (e != nullptr) *e = AssociationCache::Entry{p_world, u, q, found};
  }
  return found == AssociationOutcome::kAccepted ? Accept(p_lidar, p_world, u, q, options, c)
                                                : found;
}

// Points per chunk of a parallel association: fixed, so the split (and with
// it every result) does not depend on the thread count.
constexpr int kAssociationChunk = 256;

}  // namespace association_detail

// The one association routine. Associates every point of a scan (LiDAR
// frame, deskewed) at T_world_lidar against `search` (any type with a
// NeighborSearchTraits specialization). *out is cleared and refilled in point
// order (its capacity is reused); stats may be null. With a cache (may be
// null), points that moved less than its reuse_distance since their last
// search reuse that search; a cache of another scan size is reset first.
// on_accepted(neighbors) runs after each accepted constraint is appended, with
// the neighbours its plane was fitted to; it needs a fresh search per point,
// so it cannot be combined with a cache, nor with threads > 1. threads > 1
// searches chunks of points on up to that many threads (common/parallel.h;
// `search` is only read) and gives the same *out, *stats and cache as one.
template <class Search, class OnAccepted = association_detail::NoHook>
void AssociateWith(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_world_lidar,
                   const Search& search, const ConstraintOptions& options, ConstraintList* out,
                   AssociationStats* stats, AssociationCache* cache = nullptr,
                   OnAccepted&& on_accepted = OnAccepted(), int threads = 1) {
  using association_detail::AssociateOne;
  using Neighbors = typename NeighborSearchTraits<Search>::Neighbors;
  constexpr bool kHook = !std::is_same_v<std::decay_t<OnAccepted>, association_detail::NoHook>;
  RVLIO_CHECK(out != nullptr);
  RVLIO_CHECK(!kHook || cache == nullptr);
  RVLIO_CHECK(!kHook || threads <= 1);
  out->clear();
  out->reserve(p_lidar.size());
  double reuse2 = -1.0;
  std::vector<AssociationCache::Entry>* entries =
      association_detail::PrepareCache(cache, p_lidar.size(), &reuse2);
  auto entry = [entries](size_t i) { return entries != nullptr ? &(*entries)[i] : nullptr; };
  const PlaneThresholds planes = PlaneThresholds::From(options);
  const int n = static_cast<int>(p_lidar.size());
  const int chunks =
      (n + association_detail::kAssociationChunk - 1) / association_detail::kAssociationChunk;
  AssociationStats local;
  double sum_abs_residual = 0.0;
  // Counts and appends one point's result (in point order).
  auto record = [&](AssociationOutcome outcome, bool reused, const Constraint& c) {
    local.num_reused += reused ? 1 : 0;
    local.Count(outcome);
    if (outcome != AssociationOutcome::kAccepted) return false;
    sum_abs_residual += std::abs(c.residual);
    out->push_back(c);
    return true;
  };
  if (kHook || threads <= 1 || chunks <= 1) {
    Neighbors neighbors;
    Constraint c;
    for (int i = 0; i < n; ++i) {
      bool reused = false;
      const AssociationOutcome outcome =
          AssociateOne(p_lidar[i], T_world_lidar, search, options, planes, entry(i), reuse2,
                       &neighbors, &reused, &c);
      if (record(outcome, reused, c)) {
        if constexpr (kHook) on_accepted(neighbors);
      }
    }
  } else {
    // Each point's result in its own element, merged in point order below.
    std::vector<AssociationOutcome> outcomes(n);
    std::vector<uint8_t> reused(n);
    std::vector<Constraint> constraints(n);
    std::vector<Neighbors> neighbors(ParallelSlots(threads, chunks));
    ParallelFor(0, chunks, threads, [&](int chunk, int slot) {
      const int begin = chunk * association_detail::kAssociationChunk;
      const int end = std::min(n, begin + association_detail::kAssociationChunk);
      for (int i = begin; i < end; ++i) {
        bool r = false;
        outcomes[i] = AssociateOne(p_lidar[i], T_world_lidar, search, options, planes, entry(i),
                                   reuse2, &neighbors[slot], &r, &constraints[i]);
        reused[i] = r ? 1 : 0;
      }
    });
    for (int i = 0; i < n; ++i) record(outcomes[i], reused[i] != 0, constraints[i]);
  }
  if (local.num_accepted > 0) local.mean_abs_residual = sum_abs_residual / local.num_accepted;
  if (stats != nullptr) *stats = local;
}

// AssociateWith on the working map at T_world_imu * T_imu_lidar.
// threads as AssociateWith's.
void Associate(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_world_imu,
               const Pose3& T_imu_lidar, const VoxelMap& map, const ConstraintOptions& options,
               ConstraintList* out, AssociationStats* stats, AssociationCache* cache = nullptr,
               int threads = 1);

}  // namespace rvlio

#include "rvlio/constraints/associate.h"

#include <algorithm>
#include <cmath>

#include "rvlio/common/check.h"
#include "rvlio/constraints/plane_fit.h"

namespace rvlio {

namespace {

AssociationOutcome FromPlaneStatus(PlaneStatus status) {
  switch (status) {
    case PlaneStatus::kValid:
      return AssociationOutcome::kAccepted;
    case PlaneStatus::kTooFewPoints:
      return AssociationOutcome::kTooFewNeighbors;
    case PlaneStatus::kDegenerate:
      return AssociationOutcome::kDegenerate;
    case PlaneStatus::kLineLike:
      return AssociationOutcome::kLineLike;
    case PlaneStatus::kNotFlat:
      return AssociationOutcome::kNotFlat;
    case PlaneStatus::kFarFromPlane:
      return AssociationOutcome::kFarFromPlane;
    case PlaneStatus::kUncertain:
      return AssociationOutcome::kUncertain;
  }
  return AssociationOutcome::kDegenerate;
}

}  // namespace

const char* ToString(AssociationOutcome outcome) {
  switch (outcome) {
    case AssociationOutcome::kAccepted:
      return "accepted";
    case AssociationOutcome::kTooFewNeighbors:
      return "too_few_neighbors";
    case AssociationOutcome::kDegenerate:
      return "degenerate";
    case AssociationOutcome::kLineLike:
      return "line_like";
    case AssociationOutcome::kNotFlat:
      return "not_flat";
    case AssociationOutcome::kFarFromPlane:
      return "far_from_plane";
    case AssociationOutcome::kUncertain:
      return "uncertain";
    case AssociationOutcome::kLargeResidual:
      return "large_residual";
  }
  return "unknown";
}

void AssociationStats::Count(AssociationOutcome outcome) {
  ++num_points;
  switch (outcome) {
    case AssociationOutcome::kAccepted:
      ++num_accepted;
      break;
    case AssociationOutcome::kTooFewNeighbors:
      ++num_too_few_neighbors;
      break;
    case AssociationOutcome::kDegenerate:
      ++num_degenerate;
      break;
    case AssociationOutcome::kLineLike:
      ++num_line_like;
      break;
    case AssociationOutcome::kNotFlat:
      ++num_not_flat;
      break;
    case AssociationOutcome::kFarFromPlane:
      ++num_far_from_plane;
      break;
    case AssociationOutcome::kUncertain:
      ++num_uncertain;
      break;
    case AssociationOutcome::kLargeResidual:
      ++num_large_residual;
      break;
  }
}

namespace {

// Residual test and record of one accepted plane (paper Eq. 3).
AssociationOutcome Accept(const Eigen::Vector3d& p_lidar, const Eigen::Vector3d& p_world,
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
// with its normal oriented towards the sensor).
AssociationOutcome SearchPlane(const Eigen::Vector3d& p_world, const Eigen::Vector3d& sensor_world,
                               const VoxelMap& map, const ConstraintOptions& options,
                               NeighborBuffer* neighbors, Eigen::Vector3d* u, Eigen::Vector3d* q) {
  const int k = std::min(options.num_neighbors, kMaxNeighbors);
  if (map.KNearest(p_world, k, options.max_neighbor_distance, neighbors) < k)
    return AssociationOutcome::kTooFewNeighbors;
  const LocalPlane plane = FitLocalPlane(*neighbors, PlaneThresholds::From(options));
  if (!plane.valid()) return FromPlaneStatus(plane.status);
  // The normal's sign is arbitrary; orient it towards the sensor so that
  // records are reproducible and readable (RV only uses |u . n_alpha|).
  *u = plane.normal;
  if (u->dot(sensor_world - plane.centroid) < 0.0) *u = -*u;
  *q = plane.centroid;
  return AssociationOutcome::kAccepted;
}

}  // namespace

AssociationOutcome AssociatePoint(const Eigen::Vector3d& p_lidar, const Pose3& T_world_lidar,
                                  const VoxelMap& map, const ConstraintOptions& options,
                                  NeighborBuffer* neighbors, Constraint* out) {
  const Eigen::Vector3d p_world = T_world_lidar * p_lidar;
  Eigen::Vector3d u = Eigen::Vector3d::UnitZ(), q = Eigen::Vector3d::Zero();
  const AssociationOutcome found =
      SearchPlane(p_world, T_world_lidar.t, map, options, neighbors, &u, &q);
  if (found != AssociationOutcome::kAccepted) return found;
  return Accept(p_lidar, p_world, u, q, options, out);
}

void Associate(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_world_imu,
               const Pose3& T_imu_lidar, const VoxelMap& map, const ConstraintOptions& options,
               ConstraintList* out, AssociationStats* stats, AssociationCache* cache) {
  RVLIO_CHECK(out != nullptr);
  out->clear();
  out->reserve(p_lidar.size());
  const Pose3 T_world_lidar = T_world_imu * T_imu_lidar;
  std::vector<AssociationCache::Entry>* entries = nullptr;
  double reuse2 = -1.0;  // squared reuse distance; < 0: never reuse
  if (cache != nullptr) {
    entries = &cache->entries();
    if (entries->size() != p_lidar.size()) {
      entries->assign(p_lidar.size(), AssociationCache::Entry());
    } else {
      reuse2 = cache->reuse_distance() * cache->reuse_distance();
    }
  }
  AssociationStats local;
  double sum_abs_residual = 0.0;
  NeighborBuffer neighbors;
  Constraint c;
  Eigen::Vector3d u = Eigen::Vector3d::UnitZ(), q = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < p_lidar.size(); ++i) {
    const Eigen::Vector3d p_world = T_world_lidar * p_lidar[i];
    AssociationOutcome found;
    AssociationCache::Entry* e = entries != nullptr ? &(*entries)[i] : nullptr;
    if (e != nullptr && (p_world - e->p_world).squaredNorm() < reuse2) {
      found = e->outcome;
      u = e->normal_world;
      q = e->q_world;
      ++local.num_reused;
    } else {
      found = SearchPlane(p_world, T_world_lidar.t, map, options, &neighbors, &u, &q);
      if (e != nullptr) *e = AssociationCache::Entry{p_world, u, q, found};
    }
    const AssociationOutcome outcome = found == AssociationOutcome::kAccepted
                                           ? Accept(p_lidar[i], p_world, u, q, options, &c)
                                           : found;
    local.Count(outcome);
    if (outcome != AssociationOutcome::kAccepted) continue;
    sum_abs_residual += std::abs(c.residual);
    out->push_back(c);
  }
  if (local.num_accepted > 0) local.mean_abs_residual = sum_abs_residual / local.num_accepted;
  if (stats != nullptr) *stats = local;
}

}  // namespace rvlio

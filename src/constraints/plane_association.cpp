#include "rvlio/constraints/plane_association.h"

namespace rvlio {

namespace association_detail {

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

std::vector<AssociationCache::Entry>* PrepareCache(AssociationCache* cache, size_t n,
                                                   double* reuse2) {
  *reuse2 = -1.0;
  if (cache == nullptr) return nullptr;
  std::vector<AssociationCache::Entry>* entries = &cache->entries();
  if (entries->size() != n) {
    entries->assign(n, AssociationCache::Entry());
  } else {
    *reuse2 = cache->reuse_distance() * cache->reuse_distance();
  }
  return entries;
}

}  // namespace association_detail

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

AssociationOutcome AssociatePoint(const Eigen::Vector3d& p_lidar, const Pose3& T_world_lidar,
                                  const VoxelMap& map, const ConstraintOptions& options,
                                  NeighborBuffer* neighbors, Constraint* out) {
  const Eigen::Vector3d p_world = T_world_lidar * p_lidar;
  Eigen::Vector3d u = Eigen::Vector3d::UnitZ(), q = Eigen::Vector3d::Zero();
  const AssociationOutcome found = association_detail::SearchPlane(
      p_world, T_world_lidar.t, map, options, PlaneThresholds::From(options), neighbors, &u, &q);
  if (found != AssociationOutcome::kAccepted) return found;
  return association_detail::Accept(p_lidar, p_world, u, q, options, out);
}

void Associate(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_world_imu,
               const Pose3& T_imu_lidar, const VoxelMap& map, const ConstraintOptions& options,
               ConstraintList* out, AssociationStats* stats, AssociationCache* cache, int threads) {
  AssociateWith(p_lidar, T_world_imu * T_imu_lidar, map, options, out, stats, cache,
                association_detail::NoHook(), threads);
}

}  // namespace rvlio

#pragma once
// Point-to-plane association of one scan against the working map
// (docs/design.md section 4): for each point, transform it to the world with the
// current estimate, take its k nearest map points, fit and validate a local
// plane (plane_fit.h) and keep the constraint when |r| <= max_residual.
// Single-threaded, no per-point heap allocation, output in point order.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rvlio/constraints/constraint.h"
#include "rvlio/constraints/options.h"
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

// Associates every point of a scan (LiDAR frame, deskewed). *out is cleared
// and refilled in point order (its capacity is reused); stats may be null.
// With a cache (may be null), points that moved less than its reuse_distance
// since their last search reuse that search; a cache of another scan size is
// reset first.
void Associate(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_world_imu,
               const Pose3& T_imu_lidar, const VoxelMap& map, const ConstraintOptions& options,
               ConstraintList* out, AssociationStats* stats, AssociationCache* cache = nullptr);

}  // namespace rvlio

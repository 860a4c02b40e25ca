#pragma once
// The leave-one-out map of batch refinement (docs/design.md "The backends", "refine":
// a scan never matches its own points).
//
// It holds every scan's points in the world frame, each tagged with its scan
// id, and answers k-nearest-neighbour queries on behalf of one scan, ignoring
// that scan's points. Excluding a window of neighbouring scans instead would
// be wrong for a slow or hovering sensor (nearby scans then see the same
// surface as the scan itself and carry the information); excluding only the
// scan's own points keeps the map every other scan builds.
//
// Structure: voxels of edge MapOptions::voxel_size in a hash table, each with
// at most max_points_per_voxel entries. Like the working map (VoxelMap), a new
// point closer than min_point_distance to an entry of its voxel does not
// become an entry of its own; if the entry belongs to another scan and has no
// backup yet, the new point becomes the entry's backup. A query for scan k
// reads each entry's point, or the backup when the point is scan k's (the
// entry is skipped when it has no backup). So scan k's points never appear in
// its neighbours, and where they shadowed another scan's nearby point at
// insertion, that point stands in for them: each scan sees the map at the
// density of the full map. Memory: 32 bytes per entry.
//
// The map is built once per refinement round (all scans at the current
// estimates) and then only read, so queries from several threads are safe.
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "rvlio/constraints/plane_association.h"
#include "rvlio/constraints/constraint.h"
#include "rvlio/constraints/neighbor_search.h"
#include "rvlio/constraints/options.h"
#include "rvlio/map/options.h"
#include "rvlio/map/voxel_key.h"
#include "rvlio/map/voxel_map.h"
#include "rvlio/math/pose.h"

namespace rvlio {

// The result of one query, reused across queries: the first `size` entries
// (points, world, m; dist2, m^2), sorted by increasing distance, and the scan
// each point came from.
struct ScanNeighbors : NeighborBuffer {
  std::array<int32_t, kMaxNeighbors> scan_ids;
};

struct RefineMapStats {
  int64_t points_offered = 0;  // finite points passed to Insert
  int64_t entries = 0;         // stored entries (a point each)
  int64_t backups = 0;         // entries with a backup point of another scan
  int64_t voxels = 0;
};

class RefineMap {
 public:
  static constexpr int32_t kNoScan = -1;

  // Uses voxel_size, max_points_per_voxel and min_point_distance.
  explicit RefineMap(const MapOptions& options = MapOptions());

  // Adds the points of scan `scan_id` (>= 0; world, m). Non-finite points are
  // ignored.
  void Insert(int32_t scan_id, const std::vector<Eigen::Vector3d>& p_world);

  // Exact k nearest visible points of q_world within max_dist (m) for scan
  // `exclude_scan` (kNoScan: every entry's point is visible), sorted by
  // distance. Returns out->size. 1 <= k <= kMaxNeighbors. No heap allocation.
  int KNearest(const Eigen::Vector3d& q_world, int k, double max_dist, int32_t exclude_scan,
               ScanNeighbors* out) const;

  // Every point visible to `exclude_scan` (as KNearest sees them), with its
  // scan id: for tests and diagnostics.
  void VisiblePoints(int32_t exclude_scan, std::vector<Eigen::Vector3d>* points,
                     std::vector<int32_t>* scan_ids) const;

  void Clear();    // keeps the allocated memory
  void Release();  // Clear() and frees the memory
  const RefineMapStats& stats() const { return stats_; }

 private:
  struct Entry {
    float p[3];
    int32_t scan;
    float backup[3];
    int32_t backup_scan;  // kNoScan: no backup
  };
  struct Voxel {
    VoxelKey key;
    std::vector<Entry> entries;
  };
  class Best;

  void InsertPoint(int32_t scan_id, const Eigen::Vector3d& p);
  void ScanVoxel(const Voxel& v, const float q[3], int32_t exclude_scan, Best* best) const;
  void VisitShell(int r, const VoxelKey& home, const float q[3], int32_t exclude_scan,
                  Best* best) const;

  MapOptions options_;
  double inv_voxel_size_;
  float min_d2_;
  std::unordered_map<VoxelKey, int32_t, VoxelKeyHash> index_;  // key -> voxels_ index
  std::vector<Voxel> voxels_;
  size_t used_voxels_ = 0;  // voxels_[0, used_voxels_) are in use (the rest is spare memory)
  RefineMapStats stats_;
};

// The leave-one-out map as seen by scan `scan_id` (RefineMap::kNoScan: every
// entry's point), for the association (constraints/neighbor_search.h).
struct LeaveOneOutSearch {
  const RefineMap* map = nullptr;
  int32_t scan_id = RefineMap::kNoScan;
};

template <>
struct NeighborSearchTraits<LeaveOneOutSearch> {
  using Neighbors = ScanNeighbors;
  static int KNearest(const LeaveOneOutSearch& search, const Eigen::Vector3d& q_world, int k,
                      double max_dist, Neighbors* out) {
    return search.map->KNearest(q_world, k, max_dist, search.scan_id, out);
  }
};

// Point-to-plane association of one deskewed scan (LiDAR frame at its end)
// against the leave-one-out map on behalf of scan `scan_id`: the one
// association routine (constraints/plane_association.h, AssociateWith), with the k
// nearest points drawn only from other scans. *out is cleared and refilled in point order.
// sources (may be null) receives, per constraint, the scan that contributed
// most of the plane's neighbours (ties: the nearest neighbour's scan).
void AssociateScan(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_world_lidar,
                   int32_t scan_id, const RefineMap& map, const ConstraintOptions& options,
                   ConstraintList* out, AssociationStats* stats,
                   std::vector<int32_t>* sources = nullptr);

}  // namespace rvlio

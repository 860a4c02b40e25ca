#pragma once
// A fixed reference point cloud (a survey, an earlier map) in its own frame,
// searchable for exact k nearest neighbours; built once, never changed
// (docs/map_eval.md). It is the project's voxel-hash map (voxel_map.h) filled
// once with every point: no per-voxel cap worth speaking of (65535), no
// minimum point distance, so the nearest-point distances are those of the
// cloud itself. Points are stored in single precision, as PCD files hold
// them. The association reaches it through NeighborSearchTraits<ReferenceMap>
// (constraints/neighbor_search.h); QueryReferenceSurface
// (constraints/reference_surface.h) fits the local plane.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rvlio/common/options.h"
#include "rvlio/map/voxel_map.h"

namespace rvlio {

struct ReferenceMapOptions {
  // Edge of the hash voxels, m. A voxel's points are scanned linearly, so it
  // should hold tens of points: 0.1 m suits clouds of 1-5 cm spacing
  // (benchmark: docs/map_eval.md).
  double voxel_size = 0.1;

  template <class V>
  void Visit(V& v) {
    v.Field("voxel_size", voxel_size, Spec().Unit("m").Range(0.01, 20.0)
        .Help("hash voxel edge of a reference cloud's search structure"));
  }
};

class ReferenceMap {
 public:
  // Stores every finite point of p_ref (reference frame, m; a cloud in a
  // national grid goes into its local frame first: math/local_origin.h).
  // Points not stored (non-finite, beyond VoxelMapReach of the voxel size,
  // about 10^6 voxels from the origin, or beyond 65535 in one voxel) are
  // counted in NumSkipped(); those beyond the reach also in NumOutOfReach()
  // (CheckReach(voxels(), n) turns them into an error).
  explicit ReferenceMap(const std::vector<Eigen::Vector3d>& p_ref,
                        const ReferenceMapOptions& options = ReferenceMapOptions());
  // The same, inserting the points in `order` (a permutation of p_ref's
  // indices): VoxelOrder(p_ref, options.voxel_size), which the constructor
  // above computes, for a caller that needs that order anyway.
  ReferenceMap(const std::vector<Eigen::Vector3d>& p_ref, const std::vector<uint32_t>& order,
               const ReferenceMapOptions& options);

  // Exact k nearest stored points of q_ref within max_dist (m), sorted by
  // distance (VoxelMap::KNearest). 1 <= k <= kMaxNeighbors. No allocation.
  int KNearest(const Eigen::Vector3d& q_ref, int k, double max_dist, NeighborBuffer* out) const {
    return map_.KNearest(q_ref, k, max_dist, out);
  }

  size_t Size() const { return map_.Size(); }
  size_t NumSkipped() const { return num_skipped_; }
  size_t NumOutOfReach() const { return map_.NumOutOfReach(); }
  bool Empty() const { return map_.Empty(); }
  // Axis-aligned bounds of the stored points (empty box for an empty map).
  const Eigen::AlignedBox3d& Bounds() const { return bounds_; }
  const VoxelMap& voxels() const { return map_; }

 private:
  VoxelMap map_;
  size_t num_skipped_ = 0;
  Eigen::AlignedBox3d bounds_;
};

}  // namespace rvlio

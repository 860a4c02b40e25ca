#pragma once
// How the association (associate.h) asks a map for the nearest neighbours of
// a point, in the manner of small_gicp's nearest-neighbour traits: one
// specialization of NeighborSearchTraits per searchable type, giving
//
//   using Neighbors = ...;  // NeighborBuffer or a type derived from it
//                           // (the plane fit reads its points and size)
//   static int KNearest(const Search& search, const Eigen::Vector3d& q_world,
//                       int k, double max_dist, Neighbors* out);
//     // the exact k nearest points within max_dist (m), sorted by distance;
//     // returns out->size (< k when fewer are within max_dist)
//
// The association is a template over Search, so the call resolves at compile
// time: the per-point loop has no virtual call and each map keeps its own
// neighbour record (the refinement map adds the scan each neighbour came from).
// Specializations: VoxelMap and ReferenceMap here, LeaveOneOutSearch in
// refine/map.h.
#include <Eigen/Core>

#include "rvlio/map/reference_map.h"
#include "rvlio/map/voxel_map.h"

namespace rvlio {

template <class Search>
struct NeighborSearchTraits;

// The odometry's working map (IESKF and sliding window).
template <>
struct NeighborSearchTraits<VoxelMap> {
  using Neighbors = NeighborBuffer;
  static int KNearest(const VoxelMap& map, const Eigen::Vector3d& q_world, int k,
                      double max_dist, Neighbors* out) {
    return map.KNearest(q_world, k, max_dist, out);
  }
};

// A fixed reference cloud (localization in a prior map, map evaluation).
template <>
struct NeighborSearchTraits<ReferenceMap> {
  using Neighbors = NeighborBuffer;
  static int KNearest(const ReferenceMap& map, const Eigen::Vector3d& q_world, int k,
                      double max_dist, Neighbors* out) {
    return map.KNearest(q_world, k, max_dist, out);
  }
};

}  // namespace rvlio

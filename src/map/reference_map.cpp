#include "rvlio/map/reference_map.h"

#include "rvlio/common/check.h"
#include "rvlio/map/voxel_order.h"

namespace rvlio {

namespace {

MapOptions StaticMapOptions(const ReferenceMapOptions& options) {
  MapOptions m;
  m.voxel_size = options.voxel_size;
  m.max_points_per_voxel = 65535;  // the largest block a voxel can hold
  m.min_point_distance = 0.0;      // keep every point
  return m;
}

}  // namespace

ReferenceMap::ReferenceMap(const std::vector<Eigen::Vector3d>& p_ref,
                           const ReferenceMapOptions& options)
    : ReferenceMap(p_ref, VoxelOrder(p_ref, options.voxel_size), options) {}

ReferenceMap::ReferenceMap(const std::vector<Eigen::Vector3d>& p_ref,
                           const std::vector<uint32_t>& order, const ReferenceMapOptions& options)
    : map_(StaticMapOptions(options)) {
  RVLIO_CHECK(order.size() == p_ref.size());
  // Filled voxel by voxel: each voxel's block is allocated once, at its
  // final size, and neighbouring voxels' blocks lie close together in the pool.
  map_.InsertInVoxelOrder(p_ref, order);
  num_skipped_ = p_ref.size() - map_.Size();
  map_.ForEachPoint([this](const Eigen::Vector3d& p) { bounds_.extend(p); });  // stored (float) coordinates
}

}  // namespace rvlio

#pragma once
// A spatially coherent order of a point cloud (docs/map_eval.md, "Speed"):
// the point indices sorted voxel by voxel. A loop over many points that
// searches or fills a voxel map (map/voxel_map.h) in this order meets the
// same voxels, hash slots and point blocks again and again while they are in
// the cache; in a cloud's own order (random for a synthetic survey, a scan
// pattern for a recorded one) nearly every voxel it touches is a cache miss.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace rvlio {

// The indices 0 .. points.size() - 1 ordered by the voxel of edge
// voxel_size_m (> 0) holding each point, voxels in lexicographic (x, y, z)
// order, and within a voxel by index (a stable sort). Points that cannot be
// keyed (non-finite, or farther than ~10^9 voxels from the origin) come last,
// in index order. points.size() must be below 2^32. A radix sort over the
// occupied key range: linear in the number of points.
std::vector<uint32_t> VoxelOrder(const std::vector<Eigen::Vector3d>& points, double voxel_size_m);

// A loop over a VoxelOrder reads the points themselves in a random order of
// memory; it calls this at step j to have points[order[j + kPrefetchAhead]]
// on its way to the cache by the time it is used (a hint; no effect on
// results, none on compilers without __builtin_prefetch).
constexpr size_t kPrefetchAhead = 16;
inline void PrefetchAhead(const std::vector<Eigen::Vector3d>& points,
                          const std::vector<uint32_t>& order, size_t j) {
#if defined(__GNUC__)
  if (j + kPrefetchAhead < order.size()) __builtin_prefetch(points[order[j + kPrefetchAhead]].data());
#else
  (void)points, (void)order, (void)j;
#endif
}

}  // namespace rvlio

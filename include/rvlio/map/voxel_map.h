#pragma once
// The working map of the odometry (docs/design.md "Modules and their dependencies", map/): an
// incremental voxel-hash map with exact k-nearest-neighbour search.
//
// Points (world frame, m) live in cubic voxels of edge MapOptions::voxel_size,
// within about 10^6 voxels of the origin along each axis (VoxelMapReach:
// 104.8 km at 0.1 m voxels); farther points are not stored but counted
// (NumOutOfReach, CheckReach). Clouds in a national grid (UTM: northings of
// millions of metres) are moved into a local frame first (math/local_origin.h).
// A voxel keeps at most max_points_per_voxel points; a new point closer than
// min_point_distance to a point already in its voxel is skipped. Voxels are
// found through an open-addressing hash table (linear probing, power-of-two
// capacity, load <= 1/2) whose slots hold the voxel records. Each voxel owns a
// block of float storage laid out as x[c], y[c], z[c] (so the distance loop
// of a query vectorizes); block capacities c grow 4, 8, 16, ... up to
// max_points_per_voxel, so sparse voxels stay small. Memory is reused: freed
// blocks go to per-capacity free lists, and queries allocate nothing.
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/map/options.h"
#include "rvlio/map/voxel_key.h"

namespace rvlio {

// Largest k a query can ask for.
constexpr int kMaxNeighbors = 32;

// Result of one k-nearest query, owned by the caller and reused across
// queries: the first `size` entries, sorted by increasing distance.
struct NeighborBuffer {
  int size = 0;
  std::array<Eigen::Vector3d, kMaxNeighbors> points;  // world, m
  std::array<double, kMaxNeighbors> dist2;            // squared distance to the query, m^2
};

// The largest |coordinate| (m, per axis) a VoxelMap with voxels of
// voxel_size stores: the packed keys hold 21 bits per axis (less a margin for
// the neighbour offsets), about 1.047e6 voxels.
double VoxelMapReach(double voxel_size);

class VoxelMap {
 public:
  explicit VoxelMap(const MapOptions& options = MapOptions());

  // Inserts points (world, m). Non-finite points are ignored; points beyond
  // VoxelMapReach are counted in NumOutOfReach.
  void Insert(const std::vector<Eigen::Vector3d>& p_world);
  // Inserts one point; true when it was stored (not skipped by the voxel's
  // capacity, by min_point_distance, as non-finite or beyond the reach).
  bool InsertPoint(const Eigen::Vector3d& p_world);
  // Inserts p_world[order[0]], p_world[order[1]], ... as InsertPoint called
  // on each in that order would (the same points stored, the same results of
  // every query), for a cloud listed voxel by voxel (VoxelOrder with this
  // map's voxel size: map/voxel_order.h): the hash table and the pool grow
  // once, and each voxel's block is allocated once at its final capacity
  // instead of once per capacity class. Any other order is correct, only
  // slower. Returns the number of points stored.
  size_t InsertInVoxelOrder(const std::vector<Eigen::Vector3d>& p_world,
                            const std::vector<uint32_t>& order);

  // Exact k nearest stored points of q_world among those within max_dist (m),
  // sorted by distance into *out. Returns out->size (< k when fewer points are
  // within max_dist). 1 <= k <= kMaxNeighbors. No heap allocation.
  // With MapOptions::neighbor_search "nearby" only the query's voxel and the
  // 26 around it are searched: the k nearest of their points within
  // max_dist (the same as the exact search whenever those are the k nearest).
  int KNearest(const Eigen::Vector3d& q_world, int k, double max_dist, NeighborBuffer* out) const;

  // Removes every voxel whose centre is farther than radius (m) from
  // center_world (the sensor position: keeps a working window).
  void RemoveFar(const Eigen::Vector3d& center_world, double radius);

  void Clear();

  size_t Size() const { return num_points_; }       // stored points
  size_t NumVoxels() const { return num_voxels_; }  // occupied voxels
  // Finite points not stored since construction or Clear() because a
  // coordinate lay beyond VoxelMapReach(voxel_size).
  size_t NumOutOfReach() const { return num_out_of_reach_; }
  bool Empty() const { return num_points_ == 0; }
  const MapOptions& options() const { return options_; }

  // Calls f(const Eigen::Vector3d& p_world) for every stored point, in an
  // unspecified but deterministic order.
  template <class F>
  void ForEachPoint(F&& f) const {
    for (const Slot& s : slots_) {
      if (s.offset < 0) continue;
      const float* x = pool_.data() + s.offset;
      for (int i = 0; i < s.count; ++i)
        f(Eigen::Vector3d(x[i], x[i + s.capacity], x[i + 2 * s.capacity]));
    }
  }
  std::vector<Eigen::Vector3d> Points() const;

 private:
  // One voxel: its key and its block x[capacity], y[capacity], z[capacity]
  // at pool_[offset].
  struct Slot {
    uint64_t key = 0;     // packed voxel coordinates (voxel_map.cpp)
    int32_t offset = -1;  // -1: empty slot
    uint16_t count = 0;
    uint16_t capacity = 0;
  };
  struct Offset {
    int8_t dx, dy, dz;
    float lower_bound2;  // squared box distance bound, in voxel edges^2 (see MakeShell)
  };
  // An offset mirrored into one query octant: its lower bound scaled to this
  // map's voxels, its per-axis gap-table indices (offset + r) and the
  // packed-key difference it adds.
  struct OctantOffset {
    double lower_bound_m2;  // Offset::lower_bound2 * voxel_size^2, m^2
    uint8_t ix, iy, iz;
    uint64_t key_delta;
  };
  class Candidates;

  int FindSlot(uint64_t key) const;  // slot index, or -1
  int CreateSlot(uint64_t key);      // key must be absent; returns its slot
  bool InsertKeyable(const Eigen::Vector3d& p_world);  // InsertPoint of a point within the reach
  void ReserveSlots(size_t num_voxels);  // table room for num_voxels at load <= 1/2
  void InsertSlot(const Slot& s);    // key must be absent; no growth check
  void Rebuild(size_t capacity, const std::vector<Slot>& slots);
  int CapacityClass(int capacity) const;
  int32_t AllocateBlock(int capacity);
  void FreeBlock(int32_t offset, int capacity);
  void GrowBlock(Slot* s);
  void MoveBlock(Slot* s, int new_capacity);
  int BlockCapacity(int num_points) const;  // capacity of the class that holds num_points
  void ReserveRun(const Eigen::Vector3d& p_world, size_t num_points);

  void ScanBlock(const Slot& s, const float q[3], Candidates* c) const;
  void VisitOffset(const VoxelKey& home, int dx, int dy, int dz, double gxy2,
                   const double q_local[3], const float q[3], Candidates* c) const;
  void VisitShell(int r, const VoxelKey& home, const double q_local[3], const float q[3],
                  Candidates* c) const;
  void ScanAllVoxels(const Eigen::Vector3d& q_world, const float q[3], Candidates* c) const;

  MapOptions options_;
  double inv_voxel_size_ = 1.0;
  float min_d2_ = 0.0f;
  int max_points_ = 1;  // max_points_per_voxel
  int max_search_shell_ = std::numeric_limits<int>::max();  // 1 for the nearby search

  std::vector<Slot> slots_;
  size_t mask_ = 0;
  std::vector<float> pool_;                        // blocks of x[c], y[c], z[c]
  std::vector<std::vector<int32_t>> free_blocks_;  // freed offsets per capacity class
  std::vector<Slot> scratch_slots_;                // reused by RemoveFar / growth
  size_t num_voxels_ = 0;
  size_t num_points_ = 0;
  size_t num_out_of_reach_ = 0;

  // shells_[r]: voxel offsets with Chebyshev norm r in visiting order (see
  // MakeShell), for r <= kPrecomputedShells.
  static constexpr int kPrecomputedShells = 3;
  // shells_[r][octant]: the same mirrored into each octant (bit a set when
  // the query lies in the lower half of its voxel along axis a).
  std::array<std::array<std::vector<OctantOffset>, 8>, kPrecomputedShells + 1> shells_;
};

// Ok when `map` stored every finite point it was given; else InvalidInput
// saying how many of p_inserted (what the caller inserted) lay beyond its
// reach, how far the reach is and how far the cloud spans. For a fixed cloud
// (a reference map, a cloud under evaluation), where a dropped point would
// silently change results.
Status CheckReach(const VoxelMap& map, const std::vector<Eigen::Vector3d>& p_inserted);

}  // namespace rvlio

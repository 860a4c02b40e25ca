#pragma once
// The working map of the odometry (docs/design.md section 1, map/): an
// incremental voxel-hash map with exact k-nearest-neighbour search.
//
// Points (world frame, m) live in cubic voxels of edge MapOptions::voxel_size
// (within about 10^6 voxels of the origin; farther points are not stored).
// A voxel keeps at most max_points_per_voxel points; a new point closer than
// min_point_distance to a point already in its voxel is skipped. Voxels are
// found through an open-addressing hash table (linear probing, power-of-two
// capacity, load <= 1/2) whose slots hold keys and indices of voxel records.
// A record keeps, besides its points, the records of its 26 face-, edge- and
// corner-neighbours (-1: empty), linked when a voxel is created and unlinked
// when it is removed (as iVox keeps neighbour lists), so a query whose own
// voxel is occupied looks up one key instead of up to 27. Records do not
// move when the table grows or is rebuilt. Each voxel owns a
// block of float storage laid out as x[c], y[c], z[c] (so the distance loop
// of a query vectorizes); block capacities c grow 4, 8, 16, ... up to
// max_points_per_voxel, so sparse voxels stay small. Memory is reused: freed
// blocks go to per-capacity free lists, and queries allocate nothing.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

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

class VoxelMap {
 public:
  explicit VoxelMap(const MapOptions& options = MapOptions());

  // Inserts points (world, m). Non-finite points are ignored.
  void Insert(const std::vector<Eigen::Vector3d>& p_world);
  // Inserts one point; true when it was stored (not skipped by the voxel's
  // capacity or by min_point_distance).
  bool InsertPoint(const Eigen::Vector3d& p_world);

  // Exact k nearest stored points of q_world among those within max_dist (m),
  // sorted by distance into *out. Returns out->size (< k when fewer points are
  // within max_dist). 1 <= k <= kMaxNeighbors. No heap allocation.
  int KNearest(const Eigen::Vector3d& q_world, int k, double max_dist, NeighborBuffer* out) const;

  // Removes every voxel whose centre is farther than radius (m) from
  // center_world (the sensor position: keeps a working window).
  void RemoveFar(const Eigen::Vector3d& center_world, double radius);

  void Clear();

  size_t Size() const { return num_points_; }       // stored points
  size_t NumVoxels() const { return num_voxels_; }  // occupied voxels
  bool Empty() const { return num_points_ == 0; }
  const MapOptions& options() const { return options_; }

  // Calls f(const Eigen::Vector3d& p_world) for every stored point, in an
  // unspecified but deterministic order.
  template <class F>
  void ForEachPoint(F&& f) const {
    for (const Slot& s : slots_) {
      if (s.voxel < 0) continue;
      const Voxel& v = voxels_[s.voxel];
      const float* x = pool_.data() + v.offset;
      for (int i = 0; i < v.count; ++i)
        f(Eigen::Vector3d(x[i], x[i + v.capacity], x[i + 2 * v.capacity]));
    }
  }
  std::vector<Eigen::Vector3d> Points() const;

 private:
  // One entry of the hash table: a voxel's key and record.
  struct Slot {
    uint64_t key = 0;    // packed voxel coordinates (voxel_map.cpp)
    int32_t voxel = -1;  // index into voxels_; -1: empty slot
  };
  // One voxel: its block x[capacity], y[capacity], z[capacity] at
  // pool_[offset] and its neighbours.
  struct Voxel {
    int32_t offset = -1;  // -1: a free record
    uint16_t count = 0;
    uint16_t capacity = 0;
    // near[NearIndex(dx, dy, dz)]: the record of the voxel at that offset in
    // {-1, 0, 1}^3 (-1: empty); near[13] is the voxel itself.
    std::array<int32_t, 27> near;
  };
  struct Offset {
    int8_t dx, dy, dz;
    float lower_bound2;  // squared box distance bound, in voxel edges^2 (see MakeShell)
  };
  // An offset mirrored into one query octant: its per-axis gap-table
  // indices (offset + r), the packed-key difference it adds and, in shell 1,
  // its Voxel::near index.
  struct OctantOffset {
    float lower_bound2;
    uint8_t ix, iy, iz;
    uint8_t near;
    uint64_t key_delta;
  };
  class Candidates;

  int FindVoxel(uint64_t key) const;  // record index, or -1
  int CreateVoxel(uint64_t key);      // key must be absent; returns its record
  void InsertSlot(const Slot& s);     // key must be absent; no growth check
  void FreeVoxel(int v);              // unlinks the record and frees it and its block
  void Rebuild(size_t capacity, const std::vector<Slot>& slots);
  int CapacityClass(int capacity) const;
  int32_t AllocateBlock(int capacity);
  void FreeBlock(int32_t offset, int capacity);
  void GrowBlock(Voxel* v);

  void ScanBlock(const Voxel& v, const float q[3], Candidates* c) const;
  void VisitOffset(const VoxelKey& home, int dx, int dy, int dz, const double q_local[3],
                   const float q[3], Candidates* c) const;
  void VisitShell(int r, const VoxelKey& home, const Voxel* home_voxel, const double q_local[3],
                  const float q[3], Candidates* c) const;
  void ScanAllVoxels(const Eigen::Vector3d& q_world, const float q[3], Candidates* c) const;

  MapOptions options_;
  double inv_voxel_size_ = 1.0;
  float min_d2_ = 0.0f;
  int max_points_ = 1;  // max_points_per_voxel

  std::vector<Slot> slots_;
  size_t mask_ = 0;
  std::vector<Voxel> voxels_;                      // records, indexed by Slot::voxel
  std::vector<int32_t> free_voxels_;               // free record indices
  std::vector<float> pool_;                        // blocks of x[c], y[c], z[c]
  std::vector<std::vector<int32_t>> free_blocks_;  // freed offsets per capacity class
  std::vector<Slot> scratch_slots_;                // reused by RemoveFar / growth
  size_t num_voxels_ = 0;
  size_t num_points_ = 0;

  // shells_[r]: voxel offsets with Chebyshev norm r in visiting order (see
  // MakeShell), for r <= kPrecomputedShells.
  static constexpr int kPrecomputedShells = 3;
  // shells_[r][octant]: the same mirrored into each octant (bit a set when
  // the query lies in the lower half of its voxel along axis a).
  std::array<std::array<std::vector<OctantOffset>, 8>, kPrecomputedShells + 1> shells_;
};

}  // namespace rvlio

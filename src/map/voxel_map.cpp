#include "rvlio/map/voxel_map.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <Eigen/Geometry>

#include "rvlio/common/check.h"
#include "rvlio/common/memory.h"
#include "rvlio/map/voxel_order.h"

namespace rvlio {

namespace {

constexpr size_t kInitialCapacity = 1024;  // slots (power of two)
constexpr int kFirstBlockCapacity = 4;     // points in a new voxel's block

// Voxel keys are packed into 64 bits, 21 per axis with a bias; points whose
// voxel index reaches kKeyLimit in magnitude are not stored but counted
// (VoxelMapReach: 104.8 km from the origin at 0.1 m voxels, 524 km at 0.5 m).
constexpr int kKeyBits = 21;
constexpr int64_t kKeyBias = int64_t{1} << (kKeyBits - 1);
constexpr double kKeyLimit = static_cast<double>(kKeyBias - 1024);  // margin for neighbours
constexpr uint64_t kKeyMask = (uint64_t{1} << kKeyBits) - 1;

uint64_t PackKey(int64_t x, int64_t y, int64_t z) {
  return (static_cast<uint64_t>(x + kKeyBias) << (2 * kKeyBits)) |
         (static_cast<uint64_t>(y + kKeyBias) << kKeyBits) | static_cast<uint64_t>(z + kKeyBias);
}
VoxelKey UnpackKey(uint64_t key) {
  return VoxelKey{
      static_cast<int32_t>(static_cast<int64_t>(key >> (2 * kKeyBits)) - kKeyBias),
      static_cast<int32_t>(static_cast<int64_t>((key >> kKeyBits) & kKeyMask) - kKeyBias),
      static_cast<int32_t>(static_cast<int64_t>(key & kKeyMask) - kKeyBias)};
}
// Packed key of the voxel at offset (dx, dy, dz) from a packed key, valid
// while every coordinate stays within the biased range (no carries).
uint64_t OffsetKey(uint64_t key, int dx, int dy, int dz) {
  return key + (static_cast<uint64_t>(static_cast<int64_t>(dx)) << (2 * kKeyBits)) +
         (static_cast<uint64_t>(static_cast<int64_t>(dy)) << kKeyBits) +
         static_cast<uint64_t>(static_cast<int64_t>(dz));
}
// splitmix64 finalizer: well-mixed low bits for the power-of-two table.
uint64_t HashKey(uint64_t h) {
  h ^= h >> 30;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBull;
  h ^= h >> 31;
  return h;
}
bool InKeyRange(const Eigen::Vector3d& p, double inv_voxel_size) {
  return std::abs(p.x() * inv_voxel_size) < kKeyLimit &&
         std::abs(p.y() * inv_voxel_size) < kKeyLimit &&
         std::abs(p.z() * inv_voxel_size) < kKeyLimit;  // false for NaN
}

// Offsets of Chebyshev norm r, ordered for a query in the upper octant of
// its voxel (local coordinates in [s/2, s) on every axis): by a lower bound
// of the squared box distance, then by the number of non-zero components.
// Queries in other octants mirror the offsets (VisitShell), so the voxels
// most likely to hold the nearest points come first and tighten the bound
// before the rest can be pruned without a hash lookup.
template <class Offset>
std::vector<Offset> MakeShell(int r) {
  std::vector<Offset> shell;
  for (int dx = -r; dx <= r; ++dx)
    for (int dy = -r; dy <= r; ++dy)
      for (int dz = -r; dz <= r; ++dz)
        if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) == r)
          shell.push_back(Offset{static_cast<int8_t>(dx), static_cast<int8_t>(dy),
                                 static_cast<int8_t>(dz), 0.0f});
  // Lower bound of the gap along one axis, in voxel edges, for a query in
  // the upper half of its voxel.
  auto gap = [](int d) { return d > 0 ? d - 1.0 : (d < 0 ? -d - 0.5 : 0.0); };
  for (Offset& o : shell)
    o.lower_bound2 =
        static_cast<float>(gap(o.dx) * gap(o.dx) + gap(o.dy) * gap(o.dy) + gap(o.dz) * gap(o.dz));
  auto nonzero = [](const Offset& o) { return (o.dx != 0) + (o.dy != 0) + (o.dz != 0); };
  std::stable_sort(shell.begin(), shell.end(), [&](const Offset& a, const Offset& b) {
    if (a.lower_bound2 != b.lower_bound2) return a.lower_bound2 < b.lower_bound2;
    return nonzero(a) < nonzero(b);
  });
  return shell;
}

// Distance along one axis from q (local coordinate in the home voxel, in
// [0, s)) to the voxel at integer offset d: 0 inside the same slab.
inline double AxisGap(int d, double q_local, double s) {
  if (d > 0) return d * s - q_local;
  if (d < 0) return q_local - (d + 1) * s;
  return 0.0;
}

// Squared distance from the query to the nearest voxel of shell r (Chebyshev
// offset r): the smallest single-axis gap to the faces at offsets +-r, so no
// voxel of the shell has a smaller squared gap sum (same expressions as
// VisitOffset and VisitShell, so the bound is exact in floating point too).
inline double ShellGap(int r, const double q_local[3], double s) {
  if (r == 0) return 0.0;
  double g = AxisGap(r, q_local[0], s);
  for (int a = 0; a < 3; ++a)
    g = std::min({g, AxisGap(r, q_local[a], s), AxisGap(-r, q_local[a], s)});
  return g * g;
}

}  // namespace

// The k best candidates of one query, sorted ascending by squared distance.
// `limit` is the exclusive bound a new candidate must beat: just above
// max_dist^2 until k candidates are held, then the k-th distance.
class VoxelMap::Candidates {
 public:
  Candidates(int k, float max_d2)
      : k_(k), limit_(std::nextafter(max_d2, std::numeric_limits<float>::infinity())) {}

  float limit() const { return limit_; }
  int size() const { return n_; }
  // x of candidate i; its y and z are stride(i) and 2 stride(i) floats further.
  const float* x(int i) const { return x_[i]; }
  int stride(int i) const { return stride_[i]; }

  void Offer(float d2, const float* x, int stride) {
    // d2 < limit_ is checked by the caller.
    int i = n_ < k_ ? n_++ : k_ - 1;
    while (i > 0 && d2_[i - 1] > d2) {
      d2_[i] = d2_[i - 1];
      x_[i] = x_[i - 1];
      stride_[i] = stride_[i - 1];
      --i;
    }
    d2_[i] = d2;
    x_[i] = x;
    stride_[i] = stride;
    if (n_ == k_) limit_ = d2_[k_ - 1];
  }

 private:
  int k_;
  int n_ = 0;
  float limit_;
  std::array<float, kMaxNeighbors> d2_;
  std::array<const float*, kMaxNeighbors> x_;
  std::array<int, kMaxNeighbors> stride_;
};

VoxelMap::VoxelMap(const MapOptions& options) : options_(options) {
  RVLIO_CHECK(options.voxel_size > 0.0);
  RVLIO_CHECK(options.max_points_per_voxel >= 1 && options.max_points_per_voxel <= 65535);
  inv_voxel_size_ = 1.0 / options.voxel_size;
  min_d2_ = static_cast<float>(options.min_point_distance * options.min_point_distance);
  max_points_ = options.max_points_per_voxel;
  if (options.neighbor_search == "nearby") max_search_shell_ = 1;
  else RVLIO_CHECK(options.neighbor_search == "exact");
  free_blocks_.resize(CapacityClass(max_points_) + 1);
  const double s2 = options.voxel_size * options.voxel_size;  // as VisitShell's bound test had it
  for (int r = 0; r <= kPrecomputedShells; ++r) {
    const std::vector<Offset> shell = MakeShell<Offset>(r);
    for (int octant = 0; octant < 8; ++octant) {
      const int sx = (octant & 1) ? -1 : 1, sy = (octant & 2) ? -1 : 1, sz = (octant & 4) ? -1 : 1;
      for (const Offset& o : shell) {
        const int dx = sx * o.dx, dy = sy * o.dy, dz = sz * o.dz;
        shells_[r][octant].push_back(OctantOffset{
            o.lower_bound2 * s2, static_cast<uint8_t>(dx + r), static_cast<uint8_t>(dy + r),
            static_cast<uint8_t>(dz + r), OffsetKey(0, dx, dy, dz)});
      }
    }
  }
  Rebuild(kInitialCapacity, {});
}

void VoxelMap::Clear() {
  pool_.clear();
  for (auto& list : free_blocks_) list.clear();
  num_points_ = 0;
  num_out_of_reach_ = 0;
  Rebuild(kInitialCapacity, {});
}

// ---------------------------------------------------------------- hash table

inline int VoxelMap::FindSlot(uint64_t key) const {
  size_t i = HashKey(key) & mask_;
  while (slots_[i].offset >= 0) {
    if (slots_[i].key == key) return static_cast<int>(i);
    i = (i + 1) & mask_;
  }
  return -1;
}

void VoxelMap::InsertSlot(const Slot& s) {
  size_t i = HashKey(s.key) & mask_;
  while (slots_[i].offset >= 0) i = (i + 1) & mask_;
  slots_[i] = s;
}

void VoxelMap::Rebuild(size_t capacity, const std::vector<Slot>& slots) {
  if (slots_.capacity() < capacity) {
    std::vector<Slot>().swap(slots_);
    ReserveWithHugePages(&slots_, capacity);
  }
  slots_.assign(capacity, Slot());
  mask_ = capacity - 1;
  num_voxels_ = slots.size();
  for (const Slot& s : slots) InsertSlot(s);
}

// Grows the table (doubling) until it holds num_voxels at a load <= 1/2.
void VoxelMap::ReserveSlots(size_t num_voxels) {
  size_t capacity = slots_.size();
  while (2 * num_voxels > capacity) capacity *= 2;
  if (capacity == slots_.size()) return;
  scratch_slots_.clear();
  for (const Slot& s : slots_)
    if (s.offset >= 0) scratch_slots_.push_back(s);
  Rebuild(capacity, scratch_slots_);
}

int VoxelMap::CreateSlot(uint64_t key) {
  ReserveSlots(num_voxels_ + 1);
  Slot s;
  s.key = key;
  s.capacity = static_cast<uint16_t>(std::min(kFirstBlockCapacity, max_points_));
  s.offset = AllocateBlock(s.capacity);
  InsertSlot(s);
  ++num_voxels_;
  return FindSlot(key);
}

// ------------------------------------------------------------ block storage

// Capacities are min(4 * 2^c, max_points_) for class c = 0, 1, ...
int VoxelMap::CapacityClass(int capacity) const {
  int c = 0;
  while ((kFirstBlockCapacity << c) < capacity) ++c;
  return c;
}

int32_t VoxelMap::AllocateBlock(int capacity) {
  std::vector<int32_t>& list = free_blocks_[CapacityClass(capacity)];
  if (!list.empty()) {
    const int32_t offset = list.back();
    list.pop_back();
    return offset;
  }
  const size_t offset = pool_.size();
  RVLIO_CHECK(offset + 3 * capacity < static_cast<size_t>(std::numeric_limits<int32_t>::max()));
  if (offset + 3 * capacity > pool_.capacity())  // grown geometrically, as resize would
    ReserveWithHugePages(&pool_, std::max(2 * pool_.capacity(), offset + 3 * capacity));
  pool_.resize(offset + 3 * capacity);
  return static_cast<int32_t>(offset);
}

void VoxelMap::FreeBlock(int32_t offset, int capacity) {
  free_blocks_[CapacityClass(capacity)].push_back(offset);
}

int VoxelMap::BlockCapacity(int num_points) const {
  return std::min(kFirstBlockCapacity << CapacityClass(num_points), max_points_);
}

// Moves a full voxel to a block of the next capacity class.
void VoxelMap::GrowBlock(Slot* s) { MoveBlock(s, std::min(2 * s->capacity, max_points_)); }

// Moves a voxel's points to a block of new_capacity (a class capacity).
void VoxelMap::MoveBlock(Slot* s, int new_capacity) {
  const int32_t new_offset = AllocateBlock(new_capacity);  // may reallocate pool_
  for (int axis = 0; axis < 3; ++axis)
    std::copy_n(pool_.begin() + s->offset + axis * s->capacity, s->count,
                pool_.begin() + new_offset + axis * new_capacity);
  FreeBlock(s->offset, s->capacity);
  s->offset = new_offset;
  s->capacity = static_cast<uint16_t>(new_capacity);
}

// ------------------------------------------------------------------ updates

bool VoxelMap::InsertPoint(const Eigen::Vector3d& p_world) {
  if (!InKeyRange(p_world, inv_voxel_size_)) {
    num_out_of_reach_ += p_world.allFinite() ? 1 : 0;
    return false;
  }
  return InsertKeyable(p_world);
}

bool VoxelMap::InsertKeyable(const Eigen::Vector3d& p_world) {
  const VoxelKey k = KeyOf(p_world, inv_voxel_size_);
  const uint64_t key = PackKey(k.x, k.y, k.z);
  const float px = static_cast<float>(p_world.x());
  const float py = static_cast<float>(p_world.y());
  const float pz = static_cast<float>(p_world.z());
  int slot = FindSlot(key);
  if (slot >= 0) {
    const Slot& s = slots_[slot];
    if (s.count >= max_points_) return false;
    const float* x = pool_.data() + s.offset;
    for (int i = 0; min_d2_ > 0.0f && i < s.count; ++i) {  // no test when every point is kept
      const float dx = x[i] - px, dy = x[i + s.capacity] - py, dz = x[i + 2 * s.capacity] - pz;
      if (dx * dx + dy * dy + dz * dz < min_d2_) return false;
    }
  } else {
    slot = CreateSlot(key);
  }
  Slot& s = slots_[slot];
  if (s.count == s.capacity) GrowBlock(&s);
  float* x = pool_.data() + s.offset;
  x[s.count] = px;
  x[s.count + s.capacity] = py;
  x[s.count + 2 * s.capacity] = pz;
  ++s.count;
  ++num_points_;
  return true;
}

void VoxelMap::Insert(const std::vector<Eigen::Vector3d>& p_world) {
  for (const Eigen::Vector3d& p : p_world) InsertPoint(p);
}

size_t VoxelMap::InsertInVoxelOrder(const std::vector<Eigen::Vector3d>& p_world,
                                    const std::vector<uint32_t>& order) {
  // Pass 1: the runs of consecutive keyable points in one voxel, and the
  // room their blocks take if their voxels are new.
  std::vector<size_t> run_begin;
  size_t num_floats = 0;
  uint64_t run_key = 0;
  auto close_run = [&](size_t end) {
    if (run_begin.empty()) return;
    const size_t n = std::min<size_t>(end - run_begin.back(), max_points_);
    num_floats += 3 * static_cast<size_t>(BlockCapacity(static_cast<int>(n)));
  };
  for (size_t j = 0; j < order.size(); ++j) {
    PrefetchAhead(p_world, order, j);
    const Eigen::Vector3d& p = p_world[order[j]];
    if (!InKeyRange(p, inv_voxel_size_)) {
      num_out_of_reach_ += p.allFinite() ? 1 : 0;
      continue;
    }
    const VoxelKey k = KeyOf(p, inv_voxel_size_);
    const uint64_t key = PackKey(k.x, k.y, k.z);
    if (run_begin.empty() || key != run_key) {
      close_run(j);
      run_begin.push_back(j);
      run_key = key;
    }
  }
  close_run(order.size());
  ReserveSlots(num_voxels_ + run_begin.size());
  ReserveWithHugePages(&pool_, pool_.size() + num_floats);
  // Pass 2: each run's block sized once, then its points in order.
  const size_t before = num_points_;
  run_begin.push_back(order.size());
  for (size_t r = 0; r + 1 < run_begin.size(); ++r) {
    const size_t begin = run_begin[r], end = run_begin[r + 1];
    ReserveRun(p_world[order[begin]], end - begin);
    for (size_t j = begin; j < end; ++j) {
      PrefetchAhead(p_world, order, j);
      const Eigen::Vector3d& p = p_world[order[j]];
      if (InKeyRange(p, inv_voxel_size_)) InsertKeyable(p);  // the others are counted above
    }
  }
  return num_points_ - before;
}

// Gives the voxel of p_world (keyable) room for num_points more points in one
// block of its final capacity class.
void VoxelMap::ReserveRun(const Eigen::Vector3d& p_world, size_t num_points) {
  const VoxelKey k = KeyOf(p_world, inv_voxel_size_);
  const uint64_t key = PackKey(k.x, k.y, k.z);
  int slot = FindSlot(key);
  if (slot < 0) slot = CreateSlot(key);
  Slot& s = slots_[slot];
  const int wanted = static_cast<int>(std::min<size_t>(s.count + num_points, max_points_));
  if (wanted > s.capacity) MoveBlock(&s, BlockCapacity(wanted));
}

void VoxelMap::RemoveFar(const Eigen::Vector3d& center_world, double radius) {
  const double r2 = radius * radius;
  const double vs = options_.voxel_size;
  scratch_slots_.clear();
  bool removed = false;
  for (const Slot& s : slots_) {
    if (s.offset < 0) continue;
    const VoxelKey k = UnpackKey(s.key);
    const Eigen::Vector3d c((k.x + 0.5) * vs, (k.y + 0.5) * vs, (k.z + 0.5) * vs);
    if ((c - center_world).squaredNorm() > r2) {
      num_points_ -= s.count;
      FreeBlock(s.offset, s.capacity);
      removed = true;
    } else {
      scratch_slots_.push_back(s);
    }
  }
  if (removed) Rebuild(slots_.size(), scratch_slots_);
}

std::vector<Eigen::Vector3d> VoxelMap::Points() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(num_points_);
  ForEachPoint([&](const Eigen::Vector3d& p) { out.push_back(p); });
  return out;
}

// ------------------------------------------------------------------ queries

// Squared distances four points at a time (SSE2: the same float operations
// in the same order as the scalar tail), a compare against the current limit
// and a movemask, so a group whose points are all too far costs a few
// instructions; the points that beat the limit are offered in index order,
// each re-checked against the limit as it tightens.
void VoxelMap::ScanBlock(const Slot& s, const float q[3], Candidates* c) const {
  const float* x = pool_.data() + s.offset;
  const float* y = x + s.capacity;
  const float* z = y + s.capacity;
  const int n = s.count;
  int i = 0;
#if defined(__SSE2__)
  const __m128 qx = _mm_set1_ps(q[0]), qy = _mm_set1_ps(q[1]), qz = _mm_set1_ps(q[2]);
  for (; i + 4 <= n; i += 4) {
    const __m128 dx = _mm_sub_ps(_mm_loadu_ps(x + i), qx);
    const __m128 dy = _mm_sub_ps(_mm_loadu_ps(y + i), qy);
    const __m128 dz = _mm_sub_ps(_mm_loadu_ps(z + i), qz);
    const __m128 d2 =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    int mask = _mm_movemask_ps(_mm_cmplt_ps(d2, _mm_set1_ps(c->limit())));
    if (mask == 0) continue;
    alignas(16) float d2_lane[4];
    _mm_store_ps(d2_lane, d2);
    while (mask != 0) {
      const int lane = __builtin_ctz(static_cast<unsigned>(mask));
      mask &= mask - 1;
      if (d2_lane[lane] < c->limit()) c->Offer(d2_lane[lane], x + i + lane, s.capacity);
    }
  }
#endif
  for (; i < n; ++i) {
    const float dx = x[i] - q[0];
    const float dy = y[i] - q[1];
    const float dz = z[i] - q[2];
    const float d2 = dx * dx + dy * dy + dz * dz;
    if (d2 < c->limit()) c->Offer(d2, x + i, s.capacity);
  }
}

// Visits the voxel home + (dx, dy, dz) unless its box is already farther than
// the current limit (exact box distance from the query).
// gxy2 = gx * gx + gy * gy, the squared gaps along x and y.
inline void VoxelMap::VisitOffset(const VoxelKey& home, int dx, int dy, int dz, double gxy2,
                                  const double q_local[3], const float q[3], Candidates* c) const {
  const double gz = AxisGap(dz, q_local[2], options_.voxel_size);
  if (gxy2 + gz * gz > c->limit()) return;
  const int64_t x = int64_t{home.x} + dx, y = int64_t{home.y} + dy, z = int64_t{home.z} + dz;
  if (std::max({std::abs(x), std::abs(y), std::abs(z)}) >= kKeyBias) return;  // never stored
  const int slot = FindSlot(PackKey(x, y, z));
  if (slot >= 0) ScanBlock(slots_[slot], q, c);
}

void VoxelMap::VisitShell(int r, const VoxelKey& home, const double q_local[3], const float q[3],
                          Candidates* c) const {
  if (r > kPrecomputedShells) {
    // Whole planes and rows of the shell are skipped when their gap alone
    // exceeds the limit (the limit only shrinks, so exactly the voxels a
    // per-voxel test would skip).
    const double s = options_.voxel_size;
    for (int dx = -r; dx <= r; ++dx) {
      const double gx = AxisGap(dx, q_local[0], s);
      if (gx * gx > c->limit()) continue;
      for (int dy = -r; dy <= r; ++dy) {
        const double gy = AxisGap(dy, q_local[1], s);
        const double gxy2 = gx * gx + gy * gy;
        if (gxy2 > c->limit()) continue;
        const bool side = std::abs(dx) == r || std::abs(dy) == r;
        const int dz_step = side ? 1 : 2 * r;  // interior columns: only the two caps
        for (int dz = -r; dz <= r; dz += dz_step)
          VisitOffset(home, dx, dy, dz, gxy2, q_local, q, c);
      }
    }
    return;
  }
  // The precomputed order mirrored into the query's octant; squared gaps per
  // axis and offset come from small tables instead of per-voxel branches.
  const double s = options_.voxel_size;
  int octant = 0;
  double gap2[3][2 * kPrecomputedShells + 1];
  for (int a = 0; a < 3; ++a) {
    if (q_local[a] < 0.5 * s) octant |= 1 << a;
    for (int d = -r; d <= r; ++d) {
      const double g = AxisGap(d, q_local[a], s);
      gap2[a][d + r] = g * g;
    }
  }
  const uint64_t home_key = PackKey(home.x, home.y, home.z);  // |home| < kKeyLimit: no carries
  double limit = c->limit();                                  // changes only in ScanBlock
  for (const OctantOffset& o : shells_[r][octant]) {
    if (o.lower_bound_m2 > limit) break;  // sorted: the rest are no closer
    if (gap2[0][o.ix] + gap2[1][o.iy] + gap2[2][o.iz] > limit) continue;
    const int slot = FindSlot(home_key + o.key_delta);  // == OffsetKey(home_key, dx, dy, dz)
    if (slot < 0) continue;
    ScanBlock(slots_[slot], q, c);
    limit = c->limit();
  }
}

// Fallback when the search window holds more voxels than the table has
// slots: test every occupied voxel's box instead of hashing every offset.
void VoxelMap::ScanAllVoxels(const Eigen::Vector3d& q_world, const float q[3],
                             Candidates* c) const {
  const double s = options_.voxel_size;
  for (const Slot& slot : slots_) {
    if (slot.offset < 0) continue;
    const VoxelKey k = UnpackKey(slot.key);
    const Eigen::Vector3d lo(k.x * s, k.y * s, k.z * s);
    const Eigen::Vector3d gap =
        (lo - q_world).cwiseMax(q_world - lo - Eigen::Vector3d::Constant(s)).cwiseMax(0.0);
    if (gap.squaredNorm() > c->limit()) continue;
    ScanBlock(slot, q, c);
  }
}

int VoxelMap::KNearest(const Eigen::Vector3d& q_world, int k, double max_dist,
                       NeighborBuffer* out) const {
  RVLIO_CHECK(k >= 1 && k <= kMaxNeighbors);
  RVLIO_CHECK(out != nullptr);
  out->size = 0;
  if (num_points_ == 0 || !(max_dist > 0.0)) return 0;
  if (!InKeyRange(q_world, inv_voxel_size_)) return 0;

  const double s = options_.voxel_size;
  const double max_d = std::min(max_dist, 1.0e6 * s);
  Candidates c(k, static_cast<float>(max_d * max_d));
  const float q[3] = {static_cast<float>(q_world.x()), static_cast<float>(q_world.y()),
                      static_cast<float>(q_world.z())};
  const VoxelKey home = KeyOf(q_world, inv_voxel_size_);
  const double q_local[3] = {q_world.x() - home.x * s, q_world.y() - home.y * s,
                             q_world.z() - home.z * s};

  // Shell r lies at least (r - 1) s from any point of the home voxel, so
  // shells up to floor(max_d / s) + 1 can hold points within max_d.
  const int max_shell =
      std::min(static_cast<int>(std::floor(max_d / s)) + 1, max_search_shell_);
  // Shells are visited while the cube they cover has no more voxels than the
  // table has slots (past that one pass over every voxel costs less). They
  // settle a query as soon as the next shell lies beyond the k-th candidate,
  // usually within a few shells whatever max_dist is; only a query they leave
  // open (fewer than k points that near) scans every voxel, from scratch.
  const int cube_shell =
      static_cast<int>((std::cbrt(static_cast<double>(slots_.size())) - 1.0) / 2.0);
  bool settled = true;
  for (int r = 0; r <= max_shell; ++r) {
    if (ShellGap(r, q_local, s) > c.limit()) break;  // nothing closer remains
    if (r > cube_shell) {
      settled = false;
      break;
    }
    VisitShell(r, home, q_local, q, &c);
  }
  if (!settled) {
    c = Candidates(k, static_cast<float>(max_d * max_d));
    ScanAllVoxels(q_world, q, &c);
  }

  out->size = c.size();
  for (int i = 0; i < c.size(); ++i) {
    const float* x = c.x(i);
    out->points[i] = Eigen::Vector3d(x[0], x[c.stride(i)], x[2 * c.stride(i)]);
    out->dist2[i] = (out->points[i] - q_world).squaredNorm();
  }
  return out->size;
}

double VoxelMapReach(double voxel_size) { return kKeyLimit * voxel_size; }

Status CheckReach(const VoxelMap& map, const std::vector<Eigen::Vector3d>& p_inserted) {
  if (map.NumOutOfReach() == 0) return Status::Ok();
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : p_inserted)
    if (p.allFinite()) box.extend(p);
  const Eigen::Vector3d span_km = box.sizes() / 1000.0;
  const double reach_km = VoxelMapReach(map.options().voxel_size) / 1000.0;
  char text[400];
  std::snprintf(text, sizeof(text),
                "%zu of %zu points lie more than %.1f km from the local origin along an axis, "
                "beyond the reach of a voxel map of %g m voxels (the cloud spans %.1f x %.1f x "
                "%.1f km in x, y, z): crop it to the area of interest, or remove stray points",
                map.NumOutOfReach(), p_inserted.size(), reach_km, map.options().voxel_size,
                span_km.x(), span_km.y(), span_km.z());
  return Status::InvalidInput(text);
}

}  // namespace rvlio

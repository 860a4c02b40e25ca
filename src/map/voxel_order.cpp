#include "rvlio/map/voxel_order.h"

#include <algorithm>
#include <array>
#include <limits>
#include <memory>

#include "rvlio/common/check.h"
#include "rvlio/common/memory.h"
#include "rvlio/map/voxel_key.h"

namespace rvlio {

namespace {

constexpr int kDigitBits = 11;  // 2048 buckets: the counts stay in L1
constexpr uint64_t kUnkeyable = std::numeric_limits<uint64_t>::max();

int BitsFor(uint64_t range) {
  int bits = 0;
  while (bits < 64 && (range >> bits) != 0) ++bits;
  return bits;
}

// Packed keys: (x - min_x, y - min_y, z - min_z), x in the highest bits;
// kUnkeyable for points that have no voxel. Sets *bits to the key width.
std::vector<uint64_t> PackedKeys(const std::vector<Eigen::Vector3d>& points, double inv_voxel_size,
                                 int* bits) {
  const auto keyable = [&](const Eigen::Vector3d& p) {
    return IsKeyable(p.x(), p.y(), p.z(), inv_voxel_size);
  };
  VoxelKey lo{std::numeric_limits<int32_t>::max(), std::numeric_limits<int32_t>::max(),
              std::numeric_limits<int32_t>::max()};
  VoxelKey hi{std::numeric_limits<int32_t>::min(), std::numeric_limits<int32_t>::min(),
              std::numeric_limits<int32_t>::min()};
  for (const Eigen::Vector3d& p : points) {
    if (!keyable(p)) continue;
    const VoxelKey k = KeyOf(p, inv_voxel_size);
    lo = VoxelKey{std::min(lo.x, k.x), std::min(lo.y, k.y), std::min(lo.z, k.z)};
    hi = VoxelKey{std::max(hi.x, k.x), std::max(hi.y, k.y), std::max(hi.z, k.z)};
  }
  const auto span = [](int32_t a, int32_t b) {
    return a > b ? uint64_t{0} : static_cast<uint64_t>(int64_t{b} - a);
  };
  const int bx = BitsFor(span(lo.x, hi.x)), by = BitsFor(span(lo.y, hi.y));
  const int bz = BitsFor(span(lo.z, hi.z));
  // Each axis spans below 2^31 voxels; three such need up to 93 bits, more
  // than a key holds: beyond 63 bits the lowest z bits are dropped (voxels
  // merge along z; the order stays spatially coherent).
  const int drop_z = std::max(0, bx + by + bz - 63);
  *bits = bx + by + bz - drop_z;
  std::vector<uint64_t> packed;
  ReserveWithHugePages(&packed, points.size());
  packed.assign(points.size(), kUnkeyable);
  for (size_t i = 0; i < points.size(); ++i) {
    if (!keyable(points[i])) continue;
    const VoxelKey k = KeyOf(points[i], inv_voxel_size);
    packed[i] = (static_cast<uint64_t>(int64_t{k.x} - lo.x) << (by + bz - drop_z)) |
                (static_cast<uint64_t>(int64_t{k.y} - lo.y) << (bz - drop_z)) |
                (static_cast<uint64_t>(int64_t{k.z} - lo.z) >> drop_z);
  }
  return packed;
}

}  // namespace

std::vector<uint32_t> VoxelOrder(const std::vector<Eigen::Vector3d>& points, double voxel_size_m) {
  RVLIO_CHECK(voxel_size_m > 0.0);
  RVLIO_CHECK(points.size() < (uint64_t{1} << 32));
  const size_t n = points.size();
  int bits = 0;
  std::vector<uint64_t> keys = PackedKeys(points, 1.0 / voxel_size_m, &bits);
  std::vector<uint32_t> order;
  ReserveWithHugePages(&order, n);
  order.resize(n);
  for (size_t i = 0; i < n; ++i) order[i] = static_cast<uint32_t>(i);
  // Unkeyable points carry all ones: they sort after every key of `bits`
  // bits once one more bit is looked at.
  if (std::find(keys.begin(), keys.end(), kUnkeyable) != keys.end()) bits = std::min(64, bits + 1);
  // LSD radix sort, kDigitBits per pass: each pass is stable, so points of
  // one voxel keep their index order.
  // The passes scatter back and forth between these and a second pair left
  // uninitialized (every pass writes every entry; zeroing it would cost a
  // pass over 12 bytes per point for nothing).
  std::unique_ptr<uint64_t[]> keys_tmp(new uint64_t[n]);
  std::unique_ptr<uint32_t[]> order_tmp(new uint32_t[n]);
  AdviseHugePages(keys_tmp.get(), n * sizeof(uint64_t));
  AdviseHugePages(order_tmp.get(), n * sizeof(uint32_t));
  uint64_t *keys_from = keys.data(), *keys_to = keys_tmp.get();
  uint32_t *order_from = order.data(), *order_to = order_tmp.get();
  for (int shift = 0; shift < bits; shift += kDigitBits) {
    std::array<size_t, (size_t{1} << kDigitBits) + 1> start{};
    const auto digit = [&](uint64_t key) { return (key >> shift) & ((uint64_t{1} << kDigitBits) - 1); };
    for (size_t i = 0; i < n; ++i) ++start[digit(keys_from[i]) + 1];
    for (size_t d = 1; d < start.size(); ++d) start[d] += start[d - 1];
    for (size_t i = 0; i < n; ++i) {
      const size_t to = start[digit(keys_from[i])]++;
      keys_to[to] = keys_from[i];
      order_to[to] = order_from[i];
    }
    std::swap(keys_from, keys_to);
    std::swap(order_from, order_to);
  }
  if (order_from != order.data()) std::copy_n(order_from, n, order.data());
  return order;
}

}  // namespace rvlio

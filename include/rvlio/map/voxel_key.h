#pragma once
// Integer voxel coordinates and a fast hash for them, shared by the working
// map (voxel_map.h), the output map (output_map.h) and scan downsampling.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

namespace rvlio {

// Voxel (x, y, z) covers [x s, (x + 1) s) x [y s, (y + 1) s) x [z s, (z + 1) s)
// for voxel edge s.
struct VoxelKey {
  int32_t x = 0;
  int32_t y = 0;
  int32_t z = 0;

  bool operator==(const VoxelKey& o) const { return x == o.x && y == o.y && z == o.z; }
  bool operator!=(const VoxelKey& o) const { return !(*this == o); }
};

// Coordinates beyond this many voxels from the origin cannot be keyed (int32
// range with a margin for neighbour offsets); callers skip such points.
constexpr double kMaxVoxelIndex = 1.0e9;

// True when every coordinate of p * inv_voxel_size is finite and keyable.
inline bool IsKeyable(double x, double y, double z, double inv_voxel_size) {
  const double ax = std::abs(x * inv_voxel_size);
  const double ay = std::abs(y * inv_voxel_size);
  const double az = std::abs(z * inv_voxel_size);
  return ax < kMaxVoxelIndex && ay < kMaxVoxelIndex && az < kMaxVoxelIndex;  // false for NaN
}

// floor(v) for |v| < 2^31 without a libm call (std::floor is one on
// baseline x86-64 without SSE4.1).
inline int32_t FloorToInt(double v) {
  const int32_t i = static_cast<int32_t>(v);  // truncates towards zero
  return i - (v < static_cast<double>(i) ? 1 : 0);
}

// floor(p / voxel_size) per axis. Requires IsKeyable(p).
inline VoxelKey KeyOf(double x, double y, double z, double inv_voxel_size) {
  return VoxelKey{FloorToInt(x * inv_voxel_size), FloorToInt(y * inv_voxel_size),
                  FloorToInt(z * inv_voxel_size)};
}
inline VoxelKey KeyOf(const Eigen::Vector3d& p, double inv_voxel_size) {
  return KeyOf(p.x(), p.y(), p.z(), inv_voxel_size);
}

// 64-bit hash: the three coordinates are multiplied by large odd constants,
// combined and passed through the splitmix64 finalizer, so that the low bits
// (used by power-of-two open-addressing tables) are well mixed.
inline uint64_t HashVoxelKey(const VoxelKey& k) {
  uint64_t h = static_cast<uint64_t>(static_cast<uint32_t>(k.x)) * 0x9E3779B97F4A7C15ull;
  h ^= static_cast<uint64_t>(static_cast<uint32_t>(k.y)) * 0xC2B2AE3D27D4EB4Full;
  h ^= static_cast<uint64_t>(static_cast<uint32_t>(k.z)) * 0x165667B19E3779F9ull;
  h ^= h >> 30;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBull;
  h ^= h >> 31;
  return h;
}

struct VoxelKeyHash {
  size_t operator()(const VoxelKey& k) const { return static_cast<size_t>(HashVoxelKey(k)); }
};

}  // namespace rvlio

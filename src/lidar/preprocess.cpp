#include "rvlio/lidar/preprocess.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rvlio/common/check.h"

namespace rvlio {
namespace {

int CountTrailingZeros(uint64_t bits) {  // bits != 0
#if defined(__GNUC__) || defined(__clang__)
  return __builtin_ctzll(bits);
#else
  int n = 0;
  while ((bits & 1) == 0) bits >>= 1, ++n;
  return n;
#endif
}
}  // namespace

ScanPreprocessor::ScanPreprocessor(const LidarOptions& options)
    : range_(options),
      voxel_size_(options.voxel_size),
      inv_voxel_size_(options.voxel_size > 0.0 ? 1.0 / options.voxel_size : 0.0),
      stride_(options.point_stride) {
  // Every in-range point is keyable when max_range is far below the int32
  // limit (|coordinate| <= range): the per-point test is then skipped.
  range_keyable_ = options.max_range * inv_voxel_size_ < 0.5 * kMaxVoxelIndex;
  RVLIO_CHECK(options.voxel_size >= 0.0);
  RVLIO_CHECK(options.point_stride >= 1);
}

// Starts a new stamp: entries of earlier scans become free without clearing
// the table. The table keeps its size across scans (it only grows).
void ScanPreprocessor::BeginScan() {
  if (table_.empty()) table_.assign(1024, Entry());
  if (++stamp_ == 0) {  // wrapped: really clear once every 2^32 scans
    std::fill(table_.begin(), table_.end(), Entry());
    stamp_ = 1;
  }
  used_.clear();
}

inline size_t ScanPreprocessor::FindOrAdd(const VoxelKey& key) const {
  const size_t mask = table_.size() - 1;
  size_t slot = HashVoxelKey(key) & mask;
  while (table_[slot].stamp == stamp_ && table_[slot].key != key) slot = (slot + 1) & mask;
  return slot;
}

// Doubles the table when the load reaches 1/2, moving this scan's entries.
void ScanPreprocessor::Grow() {
  std::vector<Entry> old(2 * table_.size(), Entry());
  old.swap(table_);
  for (int32_t& slot : used_) {
    const Entry e = old[slot];
    const size_t fresh = FindOrAdd(e.key);
    table_[fresh] = e;
    slot = static_cast<int32_t>(fresh);
  }
}

// The table slot of key for the current scan, creating the entry (for point
// i at squared centre distance d2) when the voxel is new; *created tells.
inline size_t ScanPreprocessor::SlotOf(const VoxelKey& key, int i, float d2, bool* created) {
  size_t slot = FindOrAdd(key);
  *created = table_[slot].stamp != stamp_;
  if (!*created) return slot;
  if (2 * (used_.size() + 1) > table_.size()) {  // keep the load <= 1/2
    Grow();
    slot = FindOrAdd(key);
  }
  table_[slot] = Entry{key, i, d2, stamp_};
  used_.push_back(static_cast<int32_t>(slot));
  return slot;
}

// One pass: stride, finiteness and range tests, then the voxel grid. Raw
// sweeps are ordered by ring and column, so consecutive points mostly share
// a voxel: the last voxel's slot is remembered and the hash lookup skipped.
void ScanPreprocessor::FilterPoints(const Scan& scan, std::vector<int>* indices) {
  const bool grid = voxel_size_ > 0.0;
  if (grid) BeginScan();
  const double s = voxel_size_;
  const int n = stats_.num_input;
  stats_.num_strided_out = n - (n + stride_ - 1) / stride_;
  VoxelKey last_key;
  size_t last_slot = 0;
  bool have_last = false;
  for (int i = 0; i < n; i += stride_) {
    const Eigen::Vector3d p = scan.points[i].p_lidar.cast<double>();
    // r2 is finite iff the point is (float squares cannot overflow a double),
    // so one test passes the in-range points; the rare rest are sorted out.
    const double r2 = p.squaredNorm();
    if (!range_.Contains(r2)) {
      ++(std::isfinite(r2) ? stats_.num_out_of_range : stats_.num_invalid);
      continue;
    }
    if (!grid) {
      indices->push_back(i);
      continue;
    }
    if (!range_keyable_ && !IsKeyable(p.x(), p.y(), p.z(), inv_voxel_size_))
      continue;  // beyond int32 voxels
    const VoxelKey key = KeyOf(p, inv_voxel_size_);
    const Eigen::Vector3d centre((key.x + 0.5) * s, (key.y + 0.5) * s, (key.z + 0.5) * s);
    const float d2 = static_cast<float>((p - centre).squaredNorm());
    if (!have_last || key != last_key) {
      bool created = false;
      last_slot = SlotOf(key, i, d2, &created);
      last_key = key;
      have_last = true;
      if (created) continue;
    }
    Entry& e = table_[last_slot];
    if (d2 < e.d2) {  // ties keep the earlier point
      e.best = i;
      e.d2 = d2;
    }
  }
  if (grid) CollectAscending(n, indices);
}

// The kept point of every voxel, in ascending index order: a bitmap over
// the scan's points instead of sorting the indices.
void ScanPreprocessor::CollectAscending(int n, std::vector<int>* indices) {
  kept_bits_.assign((static_cast<size_t>(n) + 63) / 64, 0);
  for (const int32_t slot : used_) {
    const uint32_t i = static_cast<uint32_t>(table_[slot].best);
    kept_bits_[i / 64] |= uint64_t{1} << (i % 64);
  }
  indices->reserve(used_.size());
  for (size_t w = 0; w < kept_bits_.size(); ++w) {
    for (uint64_t bits = kept_bits_[w]; bits != 0; bits &= bits - 1) {
      indices->push_back(static_cast<int>(64 * w + static_cast<size_t>(CountTrailingZeros(bits))));
    }
  }
}

void ScanPreprocessor::SelectIndices(const Scan& scan, std::vector<int>* indices) {
  RVLIO_CHECK(indices != nullptr);
  indices->clear();
  stats_ = PreprocessStats();
  stats_.num_input = static_cast<int>(scan.points.size());
  FilterPoints(scan, indices);
  stats_.num_output = static_cast<int>(indices->size());
}

void ScanPreprocessor::Downsample(const Scan& scan, Scan* out) {
  RVLIO_CHECK(out != nullptr && out != &scan);
  SelectIndices(scan, &indices_);
  out->t_start_ns = scan.t_start_ns;
  out->t_end_ns = scan.t_end_ns;
  out->has_intensity = scan.has_intensity;
  out->has_ring = scan.has_ring;
  out->points.clear();
  out->points.reserve(indices_.size());
  for (const int i : indices_) out->points.push_back(scan.points[i]);
}

}  // namespace rvlio

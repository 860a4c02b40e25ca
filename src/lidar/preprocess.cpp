#include "rvlio/lidar/preprocess.h"

#include <algorithm>
#include <cmath>

#include "rvlio/common/check.h"

namespace rvlio {

ScanPreprocessor::ScanPreprocessor(const LidarOptions& options)
    : min_range2_(options.min_range * options.min_range),
      max_range2_(options.max_range * options.max_range),
      voxel_size_(options.voxel_size),
      inv_voxel_size_(options.voxel_size > 0.0 ? 1.0 / options.voxel_size : 0.0),
      stride_(options.point_stride) {
  RVLIO_CHECK(options.voxel_size >= 0.0);
  RVLIO_CHECK(options.point_stride >= 1);
}

void ScanPreprocessor::CollectCandidates(const Scan& scan) {
  stats_ = PreprocessStats();
  stats_.num_input = static_cast<int>(scan.points.size());
  candidates_.clear();
  for (int i = 0; i < stats_.num_input; ++i) {
    if (stride_ > 1 && i % stride_ != 0) {
      ++stats_.num_strided_out;
      continue;
    }
    const Eigen::Vector3d p = scan.points[i].p_lidar.cast<double>();
    if (!p.allFinite()) {
      ++stats_.num_invalid;
      continue;
    }
    const double r2 = p.squaredNorm();
    if (r2 < min_range2_ || r2 > max_range2_) {
      ++stats_.num_out_of_range;
      continue;
    }
    candidates_.push_back(i);
  }
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

size_t ScanPreprocessor::FindOrAdd(const VoxelKey& key) {
  const size_t mask = table_.size() - 1;
  size_t slot = HashVoxelKey(key) & mask;
  while (table_[slot].stamp == stamp_ && table_[slot].key != key) slot = (slot + 1) & mask;
  return slot;
}

// Doubles the table when the load reaches 1/2, moving this scan's entries.
void ScanPreprocessor::GrowIfNeeded() {
  if (2 * (used_.size() + 1) <= table_.size()) return;
  std::vector<Entry> old(2 * table_.size(), Entry());
  old.swap(table_);
  for (int32_t& slot : used_) {
    const Entry e = old[slot];
    const size_t fresh = FindOrAdd(e.key);
    table_[fresh] = e;
    slot = static_cast<int32_t>(fresh);
  }
}

void ScanPreprocessor::VoxelFilter(const Scan& scan, std::vector<int>* indices) {
  BeginScan();
  const double s = voxel_size_;
  for (const int i : candidates_) {
    const Eigen::Vector3d p = scan.points[i].p_lidar.cast<double>();
    if (!IsKeyable(p.x(), p.y(), p.z(), inv_voxel_size_)) continue;  // beyond int32 voxels
    const VoxelKey key = KeyOf(p, inv_voxel_size_);
    const Eigen::Vector3d centre((key.x + 0.5) * s, (key.y + 0.5) * s, (key.z + 0.5) * s);
    const float d2 = static_cast<float>((p - centre).squaredNorm());
    GrowIfNeeded();
    const size_t slot = FindOrAdd(key);
    Entry& e = table_[slot];
    if (e.stamp != stamp_) {
      e = Entry{key, i, d2, stamp_};
      used_.push_back(static_cast<int32_t>(slot));
    } else if (d2 < e.d2) {  // ties keep the earlier point
      e.best = i;
      e.d2 = d2;
    }
  }
  for (const int32_t slot : used_) indices->push_back(table_[slot].best);
  std::sort(indices->begin(), indices->end());
}

void ScanPreprocessor::SelectIndices(const Scan& scan, std::vector<int>* indices) {
  RVLIO_CHECK(indices != nullptr);
  indices->clear();
  CollectCandidates(scan);
  if (voxel_size_ > 0.0) {
    VoxelFilter(scan, indices);
  } else {
    indices->assign(candidates_.begin(), candidates_.end());
  }
  stats_.num_output = static_cast<int>(indices->size());
}

void ScanPreprocessor::Downsample(const Scan& scan, Scan* out) {
  RVLIO_CHECK(out != nullptr && out != &scan);
  SelectIndices(scan, &indices_);
  out->t_start_ns = scan.t_start_ns;
  out->t_end_ns = scan.t_end_ns;
  out->points.clear();
  out->points.reserve(indices_.size());
  for (const int i : indices_) out->points.push_back(scan.points[i]);
}

}  // namespace rvlio

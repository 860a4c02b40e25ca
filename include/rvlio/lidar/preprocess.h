#pragma once
// Scan preprocessing before association (docs/design.md "Modules and their dependencies", lidar/):
// every point_stride-th raw point, range crop to [min_range, max_range]
// (lidar/range_window.h)
// (non-finite points dropped), then a voxel grid of edge voxel_size in the
// LiDAR frame keeping one point per voxel: the one nearest the voxel centre
// (a real return, with its own time for deskew, not an average). voxel_size 0
// turns the grid off. Kept points stay in their input (acquisition) order.
//
// The preprocessor owns its workspace (a hash table of voxels and index
// buffers) and reuses it across scans: no per-point heap allocation.
#include <cstdint>
#include <vector>

#include "rvlio/common/types.h"
#include "rvlio/lidar/options.h"
#include "rvlio/lidar/range_window.h"
#include "rvlio/map/voxel_key.h"

namespace rvlio {

// A scan with fewer points after preprocessing is skipped whole (odometry and
// refine): such a scan is near-empty (sensor blocked, start-up), most of its
// points fail the plane tests, and the few constraints left would let noise
// steer the pose. A safety floor far below a real scan (a simulated OS1-32
// tunnel scan keeps ~1600 points after the 0.5 m grid: scans.csv of
// `rvlio run`), not a tuned value.
constexpr int kMinScanPoints = 50;

struct PreprocessStats {
  int num_input = 0;         // raw points
  int num_strided_out = 0;   // dropped by point_stride
  int num_invalid = 0;       // non-finite coordinates
  int num_out_of_range = 0;  // outside [min_range, max_range]
  int num_output = 0;        // kept after the voxel grid
};

class ScanPreprocessor {
 public:
  explicit ScanPreprocessor(const LidarOptions& options);

  // Indices into scan.points of the kept points, ascending.
  void SelectIndices(const Scan& scan, std::vector<int>* indices);
  // The kept points as a compact scan (same t_start_ns / t_end_ns and
  // attribute flags as the input).
  void Downsample(const Scan& scan, Scan* out);

  const PreprocessStats& stats() const { return stats_; }  // of the last call

 private:
  struct Entry {
    VoxelKey key;
    int32_t best = -1;   // index of the point kept so far
    float d2 = 0.0f;     // its squared distance to the voxel centre, m^2
    uint32_t stamp = 0;  // entry is in use for the current scan iff stamp == stamp_
  };

  void FilterPoints(const Scan& scan, std::vector<int>* indices);
  void BeginScan();
  size_t FindOrAdd(const VoxelKey& key) const;  // the key's slot, or the free slot for it
  size_t SlotOf(const VoxelKey& key, int i, float d2, bool* created);
  void Grow();
  void CollectAscending(int n, std::vector<int>* indices);

  RangeWindow range_;  // lidar.min_range .. max_range
  double voxel_size_;
  double inv_voxel_size_;
  int stride_;
  bool range_keyable_ = false;  // max_range keeps every in-range point keyable

  PreprocessStats stats_;
  std::vector<Entry> table_;     // open addressing, power-of-two size
  std::vector<int32_t> used_;    // table slots used by the current scan
  std::vector<int> indices_;     // scratch for Downsample
  std::vector<uint64_t> kept_bits_;  // one bit per input point, the kept ones set
  uint32_t stamp_ = 0;
};

}  // namespace rvlio

#pragma once
// The coarse full map written to map.pcd and map.las: every inserted point
// falls into a voxel of edge MapOptions::output_resolution, and each occupied
// voxel contributes one point: at the centroid of what fell into it (the
// surface with the range noise averaged out, as a reference map for a later
// flight needs it), with the attributes of one return, the one nearest the
// voxel's centre (the first of equals): its intensity, acquisition time, ring
// and scan index together (map/map_cloud.h), never averages of unrelated
// returns. Unbounded and insert-only (nothing is ever removed); output order
// is the order in which voxels were first touched, so it is deterministic.
// Voxels are found through an open-addressing table (linear probing,
// power-of-two capacity, load <= 1/2) of indices into the cell array. Only
// the output map holds attributes: the working map that scans are associated
// with (voxel_map.h) holds positions only.
//
// Memory: 56 bytes a voxel's cell, 12 its key, 8 to 16 the table.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/types.h"
#include "rvlio/map/map_cloud.h"
#include "rvlio/map/voxel_key.h"

namespace rvlio {

// The attributes of one inserted point.
struct MapPointAttributes {
  float intensity = 0.0f;
  TimeNs t_ns = 0;
  uint32_t scan_index = 0;
  uint16_t ring = 0;
};

// Which attributes an insertion gives (MapCloud's flags).
struct MapAttributeSet {
  bool intensity = false, time = false, ring = false, scan_index = false;
};

class OutputMap {
 public:
  explicit OutputMap(double resolution);  // m, > 0

  // Adds points (world, m) without attributes; non-finite points are ignored.
  void Insert(const std::vector<Eigen::Vector3d>& p_world);
  // Adds one scan's points (world, m): p_world[i] is the return points[i]
  // (its intensity, time and ring, as far as `scan` has them), all of scan
  // `scan_index`. Sizes must agree.
  void InsertScan(const std::vector<Eigen::Vector3d>& p_world, const Scan& scan,
                  uint32_t scan_index);
  // Adds one point with the attributes `given` says it has.
  void InsertPoint(const Eigen::Vector3d& p_world, const MapPointAttributes& a,
                   const MapAttributeSet& given);
  // Adds a cloud's points with its attributes (e.g. a chunk's map.pcd).
  void InsertCloud(const MapCloud& cloud);

  size_t Size() const { return cells_.size(); }  // occupied voxels = output points
  double resolution() const { return resolution_; }
  // The attributes every insertion gave (none before the first).
  const MapAttributeSet& attributes() const { return attributes_; }

  // One point per occupied voxel: its centroid (world, m).
  std::vector<Eigen::Vector3d> Points() const;
  // The same points with the attributes every insertion gave.
  MapCloud Cloud() const;

 private:
  struct Cell {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();  // of the points that fell in
    uint32_t count = 0;
    float d2 = 0.0f;  // the kept return's squared distance to the voxel centre, m^2
    float intensity = 0.0f;
    TimeNs t_ns = 0;
    uint32_t scan_index = 0;
    uint16_t ring = 0;
  };
  // Index into cells_ of key's voxel, creating the cell when it is new.
  size_t FindOrAddCell(const VoxelKey& key, bool* created);
  void Rehash(size_t capacity);
  void NoteAttributes(const MapAttributeSet& given);

  double resolution_;
  double inv_resolution_;
  std::vector<int32_t> table_;  // cells_ index per slot, -1: empty
  std::vector<VoxelKey> keys_;  // key of cells_[i]
  std::vector<Cell> cells_;
  MapAttributeSet attributes_;
  bool any_insert_ = false;
};

}  // namespace rvlio

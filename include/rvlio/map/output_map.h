#pragma once
// The coarse full map written to map.pcd: every inserted point falls into a
// voxel of edge MapOptions::output_resolution, and each occupied voxel
// contributes one point, the centroid of what fell into it. Unbounded and
// insert-only (nothing is ever removed); output order is the order in which
// voxels were first touched, so it is deterministic. Voxels are found through
// an open-addressing table (linear probing, power-of-two capacity, load <=
// 1/2) of indices into the cell array.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rvlio/map/voxel_key.h"

namespace rvlio {

class OutputMap {
 public:
  explicit OutputMap(double resolution);  // m, > 0

  // Adds points (world, m); non-finite points are ignored.
  void Insert(const std::vector<Eigen::Vector3d>& p_world);
  void InsertPoint(const Eigen::Vector3d& p_world);

  size_t Size() const { return cells_.size(); }  // occupied voxels = output points
  double resolution() const { return resolution_; }

  // One centroid per occupied voxel (world, m).
  std::vector<Eigen::Vector3d> Points() const;

 private:
  struct Cell {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double count = 0.0;
  };
  // Index into cells_ of key's voxel, creating the cell when it is new.
  size_t FindOrAddCell(const VoxelKey& key);
  void Rehash(size_t capacity);

  double resolution_;
  double inv_resolution_;
  std::vector<int32_t> table_;  // cells_ index per slot, -1: empty
  std::vector<VoxelKey> keys_;  // key of cells_[i]
  std::vector<Cell> cells_;
};

}  // namespace rvlio

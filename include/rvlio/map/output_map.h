#pragma once
// The coarse full map written to map.pcd: every inserted point falls into a
// voxel of edge MapOptions::output_resolution, and each occupied voxel
// contributes one point, the centroid of what fell into it. Unbounded and
// insert-only (nothing is ever removed); output order is the order in which
// voxels were first touched, so it is deterministic.
#include <cstddef>
#include <unordered_map>
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
  double resolution_;
  double inv_resolution_;
  std::unordered_map<VoxelKey, size_t, VoxelKeyHash> index_;  // key -> cells_ index
  std::vector<Cell> cells_;
};

}  // namespace rvlio

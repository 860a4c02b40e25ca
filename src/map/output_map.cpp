#include "rvlio/map/output_map.h"

#include "rvlio/common/check.h"

namespace rvlio {

OutputMap::OutputMap(double resolution)
    : resolution_(resolution), inv_resolution_(1.0 / resolution) {
  RVLIO_CHECK(resolution > 0.0);
}

void OutputMap::InsertPoint(const Eigen::Vector3d& p_world) {
  if (!IsKeyable(p_world.x(), p_world.y(), p_world.z(), inv_resolution_)) return;
  const auto inserted = index_.emplace(KeyOf(p_world, inv_resolution_), cells_.size());
  if (inserted.second) cells_.emplace_back();
  Cell& cell = cells_[inserted.first->second];
  cell.sum += p_world;
  cell.count += 1.0;
}

void OutputMap::Insert(const std::vector<Eigen::Vector3d>& p_world) {
  for (const Eigen::Vector3d& p : p_world) InsertPoint(p);
}

std::vector<Eigen::Vector3d> OutputMap::Points() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(cells_.size());
  for (const Cell& c : cells_) out.push_back(c.sum / c.count);
  return out;
}

}  // namespace rvlio

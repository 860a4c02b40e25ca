#include "rvlio/map/output_map.h"

#include <limits>

#include "rvlio/common/check.h"

namespace rvlio {

namespace {
constexpr size_t kInitialSlots = 1024;  // slots (power of two)
}  // namespace

OutputMap::OutputMap(double resolution)
    : resolution_(resolution), inv_resolution_(1.0 / resolution) {
  RVLIO_CHECK(resolution > 0.0);
  table_.assign(kInitialSlots, -1);
}

void OutputMap::Rehash(size_t capacity) {
  table_.assign(capacity, -1);
  const size_t mask = capacity - 1;
  for (size_t i = 0; i < keys_.size(); ++i) {
    size_t slot = HashVoxelKey(keys_[i]) & mask;
    while (table_[slot] >= 0) slot = (slot + 1) & mask;
    table_[slot] = static_cast<int32_t>(i);
  }
}

size_t OutputMap::FindOrAddCell(const VoxelKey& key) {
  size_t mask = table_.size() - 1;
  size_t slot = HashVoxelKey(key) & mask;
  while (table_[slot] >= 0) {
    if (keys_[table_[slot]] == key) return static_cast<size_t>(table_[slot]);
    slot = (slot + 1) & mask;
  }
  RVLIO_CHECK(cells_.size() < static_cast<size_t>(std::numeric_limits<int32_t>::max()));
  const size_t index = cells_.size();
  keys_.push_back(key);
  cells_.emplace_back();
  if (2 * cells_.size() > table_.size()) {  // keep the load <= 1/2
    Rehash(2 * table_.size());
  } else {
    table_[slot] = static_cast<int32_t>(index);
  }
  return index;
}

void OutputMap::InsertPoint(const Eigen::Vector3d& p_world) {
  if (!IsKeyable(p_world.x(), p_world.y(), p_world.z(), inv_resolution_)) return;
  Cell& cell = cells_[FindOrAddCell(KeyOf(p_world, inv_resolution_))];
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

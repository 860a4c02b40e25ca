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

size_t OutputMap::FindOrAddCell(const VoxelKey& key, bool* created) {
  size_t mask = table_.size() - 1;
  size_t slot = HashVoxelKey(key) & mask;
  *created = false;
  while (table_[slot] >= 0) {
    if (keys_[table_[slot]] == key) return static_cast<size_t>(table_[slot]);
    slot = (slot + 1) & mask;
  }
  RVLIO_CHECK(cells_.size() < static_cast<size_t>(std::numeric_limits<int32_t>::max()));
  *created = true;
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

// A map has an attribute when every insertion gave it.
void OutputMap::NoteAttributes(const MapAttributeSet& given) {
  if (!any_insert_) {
    attributes_ = given;
    any_insert_ = true;
    return;
  }
  attributes_.intensity = attributes_.intensity && given.intensity;
  attributes_.time = attributes_.time && given.time;
  attributes_.ring = attributes_.ring && given.ring;
  attributes_.scan_index = attributes_.scan_index && given.scan_index;
}

// Every point moves the centroid; the attributes are the return's nearest the
// voxel's centre (an equal one does not replace it).
void OutputMap::InsertPoint(const Eigen::Vector3d& p_world, const MapPointAttributes& a,
                            const MapAttributeSet& given) {
  NoteAttributes(given);
  if (!IsKeyable(p_world.x(), p_world.y(), p_world.z(), inv_resolution_)) return;
  const VoxelKey key = KeyOf(p_world, inv_resolution_);
  const Eigen::Vector3d centre = (Eigen::Vector3d(key.x, key.y, key.z).array() + 0.5) * resolution_;
  const float d2 = static_cast<float>((p_world - centre).squaredNorm());
  bool created = false;
  Cell& cell = cells_[FindOrAddCell(key, &created)];
  cell.sum += p_world;
  ++cell.count;
  if (!created && !(d2 < cell.d2)) return;
  cell.d2 = d2;
  cell.intensity = a.intensity;
  cell.t_ns = a.t_ns;
  cell.scan_index = a.scan_index;
  cell.ring = a.ring;
}

void OutputMap::Insert(const std::vector<Eigen::Vector3d>& p_world) {
  for (const Eigen::Vector3d& p : p_world) InsertPoint(p, MapPointAttributes{}, MapAttributeSet{});
}

void OutputMap::InsertScan(const std::vector<Eigen::Vector3d>& p_world, const Scan& scan,
                           uint32_t scan_index) {
  RVLIO_CHECK(p_world.size() == scan.points.size());
  const MapAttributeSet given{scan.has_intensity, true, scan.has_ring, true};
  MapPointAttributes a;
  a.scan_index = scan_index;
  for (size_t i = 0; i < p_world.size(); ++i) {
    const LidarPoint& q = scan.points[i];
    a.intensity = q.intensity;
    a.t_ns = q.t_ns;
    a.ring = q.ring;
    InsertPoint(p_world[i], a, given);
  }
}

void OutputMap::InsertCloud(const MapCloud& cloud) {
  RVLIO_CHECK(cloud.Consistent());
  const MapAttributeSet given{cloud.has_intensity, cloud.has_time, cloud.has_ring,
                              cloud.has_scan_index};
  MapPointAttributes a;
  for (size_t i = 0; i < cloud.size(); ++i) {
    if (given.intensity) a.intensity = cloud.intensity[i];
    if (given.time) a.t_ns = cloud.t_ns[i];
    if (given.ring) a.ring = cloud.ring[i];
    if (given.scan_index) a.scan_index = cloud.scan_index[i];
    InsertPoint(cloud.p[i], a, given);
  }
}

std::vector<Eigen::Vector3d> OutputMap::Points() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(cells_.size());
  for (const Cell& c : cells_) out.push_back(c.sum / static_cast<double>(c.count));
  return out;
}

MapCloud OutputMap::Cloud() const {
  MapCloud m;
  m.p = Points();
  m.has_intensity = attributes_.intensity;
  m.has_time = attributes_.time;
  m.has_ring = attributes_.ring;
  m.has_scan_index = attributes_.scan_index;
  for (const Cell& c : cells_) {
    if (m.has_intensity) m.intensity.push_back(c.intensity);
    if (m.has_time) m.t_ns.push_back(c.t_ns);
    if (m.has_ring) m.ring.push_back(c.ring);
    if (m.has_scan_index) m.scan_index.push_back(c.scan_index);
  }
  return m;
}

}  // namespace rvlio

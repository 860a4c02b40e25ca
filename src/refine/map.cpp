#include "rvlio/refine/map.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "rvlio/common/check.h"

namespace rvlio {

// The k best candidates so far, sorted by distance (insertion sort: k <= 32).
class RefineMap::Best {
 public:
  Best(int k, double max_dist2) : k_(k), max_d2_(max_dist2) {}

  void Offer(const float p[3], int32_t scan, float d2) {
    if (!(d2 <= max_d2_)) return;
    if (n_ == k_ && d2 >= d2_[n_ - 1]) return;
    int i = n_ < k_ ? n_++ : n_ - 1;
    for (; i > 0 && d2_[i - 1] > d2; --i) {
      d2_[i] = d2_[i - 1];
      p_[i] = p_[i - 1];
      scan_[i] = scan_[i - 1];
    }
    d2_[i] = d2;
    p_[i] = {p[0], p[1], p[2]};
    scan_[i] = scan;
  }
  bool Full() const { return n_ == k_; }
  float Worst() const { return d2_[n_ - 1]; }

  int CopyTo(ScanNeighbors* out) const {
    out->size = n_;
    for (int i = 0; i < n_; ++i) {
      out->points[i] = Eigen::Vector3d(p_[i][0], p_[i][1], p_[i][2]);
      out->dist2[i] = d2_[i];
      out->scan_ids[i] = scan_[i];
    }
    return n_;
  }

 private:
  int k_;
  int n_ = 0;
  float max_d2_;
  std::array<float, kMaxNeighbors> d2_;
  std::array<std::array<float, 3>, kMaxNeighbors> p_;
  std::array<int32_t, kMaxNeighbors> scan_;
};

namespace {

float Dist2(const float a[3], const float b[3]) {
  const float dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return dx * dx + dy * dy + dz * dz;
}

}  // namespace

RefineMap::RefineMap(const MapOptions& options)
    : options_(options),
      inv_voxel_size_(1.0 / options.voxel_size),
      min_d2_(static_cast<float>(options.min_point_distance * options.min_point_distance)) {
  RVLIO_CHECK(options.voxel_size > 0.0 && options.max_points_per_voxel >= 1);
}

void RefineMap::Clear() {
  for (size_t i = 0; i < used_voxels_; ++i) voxels_[i].entries.clear();
  used_voxels_ = 0;
  index_.clear();
  stats_ = RefineMapStats();
}

void RefineMap::Release() {
  Clear();
  std::vector<Voxel>().swap(voxels_);
  decltype(index_)().swap(index_);
}

void RefineMap::Insert(int32_t scan_id, const std::vector<Eigen::Vector3d>& p_world) {
  RVLIO_CHECK(scan_id >= 0);
  for (const Eigen::Vector3d& p : p_world) {
    if (!IsKeyable(p.x(), p.y(), p.z(), inv_voxel_size_)) continue;
    ++stats_.points_offered;
    InsertPoint(scan_id, p);
  }
}

void RefineMap::InsertPoint(int32_t scan_id, const Eigen::Vector3d& p) {
  const VoxelKey key = KeyOf(p, inv_voxel_size_);
  auto [it, created] = index_.try_emplace(key, static_cast<int32_t>(used_voxels_));
  if (created) {
    if (used_voxels_ == voxels_.size()) voxels_.emplace_back();
    voxels_[used_voxels_].key = key;
    ++used_voxels_;
    ++stats_.voxels;
  }
  std::vector<Entry>& entries = voxels_[static_cast<size_t>(it->second)].entries;
  const float q[3] = {static_cast<float>(p.x()), static_cast<float>(p.y()),
                      static_cast<float>(p.z())};
  for (Entry& e : entries) {
    if (Dist2(e.p, q) >= min_d2_) continue;
    // Shadowed by an entry: at most its backup, and only from another scan.
    if (e.backup_scan == kNoScan && e.scan != scan_id) {
      std::copy(q, q + 3, e.backup);
      e.backup_scan = scan_id;
      ++stats_.backups;
    }
    return;
  }
  if (static_cast<int>(entries.size()) >= options_.max_points_per_voxel) return;
  entries.push_back(Entry{{q[0], q[1], q[2]}, scan_id, {0.0f, 0.0f, 0.0f}, kNoScan});
  ++stats_.entries;
}

void RefineMap::ScanVoxel(const Voxel& v, const float q[3], int32_t exclude_scan,
                          Best* best) const {
  for (const Entry& e : v.entries) {
    if (e.scan != exclude_scan) {
      best->Offer(e.p, e.scan, Dist2(e.p, q));
    } else if (e.backup_scan != kNoScan) {  // backup_scan != scan by construction
      best->Offer(e.backup, e.backup_scan, Dist2(e.backup, q));
    }
  }
}

// Voxels at Chebyshev distance exactly r from home.
void RefineMap::VisitShell(int r, const VoxelKey& home, const float q[3], int32_t exclude_scan,
                           Best* best) const {
  for (int dx = -r; dx <= r; ++dx)
    for (int dy = -r; dy <= r; ++dy)
      for (int dz = -r; dz <= r; ++dz) {
        if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r) continue;
        const auto it = index_.find(VoxelKey{home.x + dx, home.y + dy, home.z + dz});
        if (it != index_.end()) ScanVoxel(voxels_[static_cast<size_t>(it->second)], q,
                                          exclude_scan, best);
      }
}

// Shells of voxels around the query's voxel, nearest first. A point in a
// voxel at Chebyshev distance r + 1 is at least r voxel edges away from any
// point of the home voxel, so the search stops after shell r once k points
// are within r edges (exact), or when r edges exceed max_dist.
int RefineMap::KNearest(const Eigen::Vector3d& q_world, int k, double max_dist,
                        int32_t exclude_scan, ScanNeighbors* out) const {
  RVLIO_CHECK(k >= 1 && k <= kMaxNeighbors);
  out->size = 0;
  if (!IsKeyable(q_world.x(), q_world.y(), q_world.z(), inv_voxel_size_) || index_.empty())
    return 0;
  const VoxelKey home = KeyOf(q_world, inv_voxel_size_);
  const float q[3] = {static_cast<float>(q_world.x()), static_cast<float>(q_world.y()),
                      static_cast<float>(q_world.z())};
  Best best(k, max_dist * max_dist);
  for (int r = 0;; ++r) {
    VisitShell(r, home, q, exclude_scan, &best);
    const double reach = r * options_.voxel_size;  // every unvisited point is farther
    if (reach >= max_dist) break;
    if (best.Full() && best.Worst() <= reach * reach) break;
  }
  return best.CopyTo(out);
}

void RefineMap::VisiblePoints(int32_t exclude_scan, std::vector<Eigen::Vector3d>* points,
                              std::vector<int32_t>* scan_ids) const {
  points->clear();
  scan_ids->clear();
  for (size_t i = 0; i < used_voxels_; ++i)
    for (const Entry& e : voxels_[i].entries) {
      const bool own = e.scan == exclude_scan;
      if (own && e.backup_scan == kNoScan) continue;
      const float* p = own ? e.backup : e.p;
      points->emplace_back(p[0], p[1], p[2]);
      scan_ids->push_back(own ? e.backup_scan : e.scan);
    }
}

namespace {

// The scan contributing most neighbours; ties go to the nearer one (the
// neighbours are sorted by distance).
int32_t MajorityScan(const ScanNeighbors& nb) {
  int32_t best = nb.scan_ids[0];
  int best_count = 0;
  for (int i = 0; i < nb.size; ++i) {
    int count = 0;
    for (int j = 0; j < nb.size; ++j) count += nb.scan_ids[j] == nb.scan_ids[i] ? 1 : 0;
    if (count > best_count) {
      best_count = count;
      best = nb.scan_ids[i];
    }
  }
  return best;
}

}  // namespace

void AssociateScan(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_world_lidar,
                   int32_t scan_id, const RefineMap& map, const ConstraintOptions& options,
                   ConstraintList* out, AssociationStats* stats, std::vector<int32_t>* sources) {
  const LeaveOneOutSearch search{&map, scan_id};
  if (sources == nullptr) {
    AssociateWith(p_lidar, T_world_lidar, search, options, out, stats);
    return;
  }
  sources->clear();
  AssociateWith(p_lidar, T_world_lidar, search, options, out, stats, nullptr,
                [sources](const ScanNeighbors& nb) { sources->push_back(MajorityScan(nb)); });
}

}  // namespace rvlio

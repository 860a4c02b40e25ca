// Deviation of a map from the reference (odometry/deviation.h).
#include "rvlio/odometry/deviation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "rvlio/map/voxel_key.h"

namespace rvlio {
namespace {

constexpr double kSampleStepM = 0.25;  // trajectory resampling along its length
constexpr double kCellM = 2.0;         // hash cell of the samples
constexpr int kMaxRings = 25;          // search up to ~50 m from a point

struct Sample {
  Eigen::Vector3d p;
  double chainage_m;
};

// Positions every kSampleStepM along the trajectory with their chainage.
std::vector<Sample> Resample(const Trajectory& t) {
  std::vector<Sample> s{{t.front().p_world_imu, 0.0}};
  double chainage = 0.0;
  for (size_t i = 1; i < t.size(); ++i) {
    const Eigen::Vector3d a = t[i - 1].p_world_imu, b = t[i].p_world_imu;
    const double len = (b - a).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / kSampleStepM)));
    for (int k = 1; k <= n; ++k)
      s.push_back({a + (b - a) * (static_cast<double>(k) / n), chainage + len * k / n});
    chainage += len;
  }
  return s;
}

// The samples in hash cells, searched ring by ring around a point.
class SampleGrid {
 public:
  explicit SampleGrid(std::vector<Sample> samples) : samples_(std::move(samples)) {
    for (size_t i = 0; i < samples_.size(); ++i)
      cells_[KeyOf(samples_[i].p, 1.0 / kCellM)].push_back(static_cast<int>(i));
  }
  // The nearest sample within kMaxRings cells, or null.
  const Sample* Nearest(const Eigen::Vector3d& q) const {
    const VoxelKey home = KeyOf(q, 1.0 / kCellM);
    const Sample* best = nullptr;
    double best2 = std::numeric_limits<double>::infinity();
    for (int r = 0; r <= kMaxRings; ++r) {
      // Every sample in ring r is at least (r - 1) cells away.
      const double bound = std::max(0, r - 1) * kCellM;
      if (best != nullptr && bound * bound > best2) break;
      VisitRing(home, r, [&](int i) {
        const double d2 = (samples_[i].p - q).squaredNorm();
        if (d2 < best2) best2 = d2, best = &samples_[i];
      });
    }
    return best;
  }

 private:
  template <class F>
  void VisitRing(const VoxelKey& home, int r, F&& f) const {
    for (int dx = -r; dx <= r; ++dx)
      for (int dy = -r; dy <= r; ++dy)
        for (int dz = -r; dz <= r; ++dz) {
          if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r) continue;
          const auto it = cells_.find(VoxelKey{home.x + dx, home.y + dy, home.z + dz});
          if (it == cells_.end()) continue;
          for (int i : it->second) f(i);
        }
  }

  std::vector<Sample> samples_;
  std::unordered_map<VoxelKey, std::vector<int>, VoxelKeyHash> cells_;
};

double Quantile(std::vector<double>* v, double q) {
  const size_t k = std::min(v->size() - 1, static_cast<size_t>(q * static_cast<double>(v->size())));
  std::nth_element(v->begin(), v->begin() + k, v->end());
  return (*v)[k];
}

double Median(std::vector<double> v) {
  const size_t n = v.size();
  std::sort(v.begin(), v.end());
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

PointDeviations ComputeDeviations(const std::vector<Eigen::Vector3d>& p_map,
                                  const ReferenceMap& reference, const Trajectory& trajectory,
                                  const SurfaceQueryOptions& options) {
  const SampleGrid grid(Resample(trajectory));
  PointDeviations d;
  d.deviation_m.resize(p_map.size(), std::numeric_limits<double>::quiet_NaN());
  d.chainage_m.resize(p_map.size(), std::numeric_limits<double>::quiet_NaN());
  NeighborBuffer neighbors;
  for (size_t i = 0; i < p_map.size(); ++i) {
    const Sample* view = grid.Nearest(p_map[i]);
    if (view == nullptr) continue;
    d.chainage_m[i] = view->chainage_m;
    const SurfaceDistance s =
        QueryReferenceSurface(reference, p_map[i], options, &neighbors, &view->p);
    if (s.has_surface()) d.deviation_m[i] = s.signed_m;
  }
  return d;
}

std::vector<DeviationBin> BinByChainage(const PointDeviations& d, double step_m) {
  std::vector<std::vector<double>> bins;
  for (size_t i = 0; i < d.deviation_m.size(); ++i) {
    if (!std::isfinite(d.deviation_m[i]) || !std::isfinite(d.chainage_m[i])) continue;
    const size_t b = static_cast<size_t>(std::max(0.0, d.chainage_m[i]) / step_m);
    if (b >= bins.size()) bins.resize(b + 1);
    bins[b].push_back(d.deviation_m[i]);
  }
  std::vector<DeviationBin> out(bins.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (size_t b = 0; b < bins.size(); ++b) {
    DeviationBin& o = out[b];
    o.chainage_m = static_cast<double>(b) * step_m;
    o.count = static_cast<int>(bins[b].size());
    if (bins[b].empty()) {
      o.median_m = o.median_abs_m = o.p95_abs_m = o.max_abs_m = nan;
      continue;
    }
    o.median_m = Median(bins[b]);
    std::vector<double> a(bins[b].size());
    std::transform(bins[b].begin(), bins[b].end(), a.begin(), [](double x) { return std::abs(x); });
    o.max_abs_m = *std::max_element(a.begin(), a.end());
    o.median_abs_m = Median(a);
    o.p95_abs_m = Quantile(&a, 0.95);
  }
  return out;
}

}  // namespace rvlio

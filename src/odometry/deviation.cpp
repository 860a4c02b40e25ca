// Deviation of a map from the reference (odometry/deviation.h).
#include "rvlio/odometry/deviation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "rvlio/common/median.h"

namespace rvlio {
namespace {

constexpr double kSampleStepM = 0.25;  // trajectory resampling along its length
constexpr double kMaxSampleDistanceM = 50.0;  // a point farther from the trajectory has no chainage

struct Sample {
  Eigen::Vector3d p;
  double chainage_m;
  Eigen::Vector3d forward;  // unit direction of travel there (zero while not moving)
};

// Positions every kSampleStepM along the trajectory with their chainage and
// direction of travel (the first sample takes the first segment's).
std::vector<Sample> Resample(const Trajectory& t) {
  std::vector<Sample> s{{t.front().p_world_imu, 0.0, Eigen::Vector3d::Zero()}};
  double chainage = 0.0;
  for (size_t i = 1; i < t.size(); ++i) {
    const Eigen::Vector3d a = t[i - 1].p_world_imu, b = t[i].p_world_imu;
    const double len = (b - a).norm();
    const Eigen::Vector3d forward = len > 0.0 ? Eigen::Vector3d((b - a) / len) : Eigen::Vector3d::Zero();
    if (s.size() == 1 && len > 0.0) s.front().forward = forward;
    const int n = std::max(1, static_cast<int>(std::ceil(len / kSampleStepM)));
    for (int k = 1; k <= n; ++k)
      s.push_back({a + (b - a) * (static_cast<double>(k) / n), chainage + len * k / n, forward});
    chainage += len;
  }
  return s;
}

// TunnelSide (deviation.h) of p_world on a reference plane of unit normal
// `normal`, seen from `view`.
TunnelSide SideOf(const Eigen::Vector3d& p_world, const Eigen::Vector3d& normal,
                  const Sample& view) {
  const Eigen::Vector3d& forward = view.forward;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ() - forward.z() * forward;
  if (forward.isZero() || up.norm() < 0.1) return TunnelSide::kNone;  // within ~6 deg of vertical
  const Eigen::Vector3d up_across = up.normalized();
  const Eigen::Vector3d left = up_across.cross(forward);
  const Eigen::Vector3d d = p_world - view.p;
  if (std::abs(normal.dot(up_across)) >= std::abs(normal.dot(left)))
    return d.dot(up_across) > 0.0 ? TunnelSide::kCeiling : TunnelSide::kFloor;
  return d.dot(left) > 0.0 ? TunnelSide::kLeft : TunnelSide::kRight;
}

// The samples in an implicit k-d tree (the median of each range splits it
// along the axis of the range's largest extent), so the nearest sample costs
// O(log n) wherever the point is. A grid of cells searched ring by ring
// costs (2r+1)^3 cells for a point r cells away: map points tens of metres
// ahead of the flight's end made that the run's dominant cost.
class SampleTree {
 public:
  explicit SampleTree(std::vector<Sample> samples)
      : samples_(std::move(samples)), axis_(samples_.size(), 0) {
    Build(0, samples_.size());
  }
  // The nearest sample within kMaxSampleDistanceM, or null.
  const Sample* Nearest(const Eigen::Vector3d& q) const {
    const Sample* best = nullptr;
    double best2 = kMaxSampleDistanceM * kMaxSampleDistanceM;
    Search(0, samples_.size(), q, &best2, &best);
    return best;
  }

 private:
  void Build(size_t lo, size_t hi) {
    if (hi - lo < 2) return;
    Eigen::Vector3d lo_p = samples_[lo].p, hi_p = samples_[lo].p;
    for (size_t i = lo; i < hi; ++i) lo_p = lo_p.cwiseMin(samples_[i].p), hi_p = hi_p.cwiseMax(samples_[i].p);
    int axis = 0;
    (hi_p - lo_p).maxCoeff(&axis);
    const size_t mid = lo + (hi - lo) / 2;
    std::nth_element(samples_.begin() + lo, samples_.begin() + mid, samples_.begin() + hi,
                     [axis](const Sample& a, const Sample& b) { return a.p[axis] < b.p[axis]; });
    axis_[mid] = axis;
    Build(lo, mid);
    Build(mid + 1, hi);
  }
  void Search(size_t lo, size_t hi, const Eigen::Vector3d& q, double* best2,
              const Sample** best) const {
    if (lo >= hi) return;
    const size_t mid = lo + (hi - lo) / 2;
    const Sample& s = samples_[mid];
    const double d2 = (s.p - q).squaredNorm();
    if (d2 < *best2) *best2 = d2, *best = &s;
    const double diff = q[axis_[mid]] - s.p[axis_[mid]];
    const bool below = diff < 0.0;
    Search(below ? lo : mid + 1, below ? mid : hi, q, best2, best);
    if (diff * diff < *best2) Search(below ? mid + 1 : lo, below ? hi : mid, q, best2, best);
  }

  std::vector<Sample> samples_;
  std::vector<int> axis_;  // split axis of the node at each index
};

double Quantile(std::vector<double>* v, double q) {
  const size_t k = std::min(v->size() - 1, static_cast<size_t>(q * static_cast<double>(v->size())));
  std::nth_element(v->begin(), v->begin() + k, v->end());
  return (*v)[k];
}

// Count, signed median and p95 |deviation| of the values.
DeviationBin::Side SideStats(const std::vector<double>& v) {
  DeviationBin::Side o;
  o.count = static_cast<int>(v.size());
  if (v.empty()) {
    o.median_m = o.p95_abs_m = std::numeric_limits<double>::quiet_NaN();
    return o;
  }
  o.median_m = Median(v);
  std::vector<double> a(v.size());
  std::transform(v.begin(), v.end(), a.begin(), [](double x) { return std::abs(x); });
  o.p95_abs_m = Quantile(&a, 0.95);
  return o;
}

}  // namespace

const char* TunnelSideName(TunnelSide side) {
  switch (side) {
    case TunnelSide::kLeft: return "left";
    case TunnelSide::kRight: return "right";
    case TunnelSide::kFloor: return "floor";
    case TunnelSide::kCeiling: return "ceiling";
    case TunnelSide::kNone: break;
  }
  return "none";
}

PointDeviations ComputeDeviations(const std::vector<Eigen::Vector3d>& p_map,
                                  const ReferenceMap& reference, const Trajectory& trajectory,
                                  const SurfaceQueryOptions& options) {
  const SampleTree samples(Resample(trajectory));
  PointDeviations d;
  d.deviation_m.resize(p_map.size(), std::numeric_limits<double>::quiet_NaN());
  d.chainage_m.resize(p_map.size(), std::numeric_limits<double>::quiet_NaN());
  d.side.resize(p_map.size(), TunnelSide::kNone);
  NeighborBuffer neighbors;
  for (size_t i = 0; i < p_map.size(); ++i) {
    const Sample* view = samples.Nearest(p_map[i]);
    if (view == nullptr) continue;
    d.chainage_m[i] = view->chainage_m;
    const SurfaceDistance s =
        QueryReferenceSurface(reference, p_map[i], options, &neighbors, &view->p);
    if (!s.has_surface()) continue;
    d.deviation_m[i] = s.signed_m;
    d.side[i] = SideOf(p_map[i], s.normal, *view);
  }
  return d;
}

std::vector<DeviationBin> BinByChainage(const PointDeviations& d, double step_m) {
  std::vector<std::vector<double>> bins;
  std::vector<std::array<std::vector<double>, kTunnelSides>> side_bins;
  for (size_t i = 0; i < d.deviation_m.size(); ++i) {
    if (!std::isfinite(d.deviation_m[i]) || !std::isfinite(d.chainage_m[i])) continue;
    const size_t b = static_cast<size_t>(std::max(0.0, d.chainage_m[i]) / step_m);
    if (b >= bins.size()) bins.resize(b + 1), side_bins.resize(b + 1);
    bins[b].push_back(d.deviation_m[i]);
    const TunnelSide side = i < d.side.size() ? d.side[i] : TunnelSide::kNone;
    if (side != TunnelSide::kNone) side_bins[b][static_cast<int>(side)].push_back(d.deviation_m[i]);
  }
  std::vector<DeviationBin> out(bins.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (size_t b = 0; b < bins.size(); ++b) {
    DeviationBin& o = out[b];
    o.chainage_m = static_cast<double>(b) * step_m;
    o.count = static_cast<int>(bins[b].size());
    for (int k = 0; k < kTunnelSides; ++k) o.sides[k] = SideStats(side_bins[b][k]);
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

#include "rvlio/eval/map_metrics.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <Eigen/Eigenvalues>

#include "rvlio/common/parallel.h"
#include "rvlio/map/voxel_order.h"
#include "rvlio/math/local_origin.h"

namespace rvlio {

namespace {

constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();
constexpr int kChunk = 4096;  // points per parallel work item (fixed: results independent of threads)

// Per MAP point: nearest distance (NaN beyond the search radius) and
// |point-to-plane| (NaN without a valid plane).
struct MapPointDistances {
  std::vector<double> nearest_m, plane_m;
};

// Counts the points searched (from every thread) and reports the share of
// `total` done, from the calling thread only (ParallelFor's slot 0), so the
// callback needs no locking.
class SearchProgress {
 public:
  SearchProgress(const MapEvalProgress& fn, size_t total) : fn_(fn), total_(total) {}
  void Done(size_t points, int slot) {
    const size_t done = done_.fetch_add(points) + points;
    if (fn_ && slot == 0) fn_(static_cast<double>(done) / static_cast<double>(total_));
  }

 private:
  const MapEvalProgress& fn_;
  const size_t total_;
  std::atomic<size_t> done_{0};
};

// order: VoxelOrder(map_points, options.search.voxel_size).
MapPointDistances MapToReference(const std::vector<Eigen::Vector3d>& map_points,
                                 const std::vector<uint32_t>& order, const ReferenceMap& ref,
                                 const MapEvalOptions& options, SearchProgress* progress) {
  MapPointDistances d;
  const size_t n = map_points.size();
  d.nearest_m.assign(n, kNoValue);
  d.plane_m.assign(n, kNoValue);
  SurfaceQueryOptions surface = options.surface;
  // The plane search must reach at least as far as the inlier test.
  surface.search_radius = std::max(surface.search_radius, options.max_distance);
  // Queried voxel by voxel so that consecutive queries meet the same
  // reference voxels in the cache; each result goes to its own index, so the
  // numbers do not depend on the order.
  const int chunks = static_cast<int>((n + kChunk - 1) / kChunk);
  ParallelFor(0, chunks, options.threads, [&](int chunk, int slot) {
    NeighborBuffer neighbors;
    const size_t begin = static_cast<size_t>(chunk) * kChunk;
    const size_t end = std::min(n, begin + kChunk);
    for (size_t j = begin; j < end; ++j) {
      PrefetchAhead(map_points, order, j);
      const size_t i = order[j];
      const SurfaceDistance s = QueryReferenceSurface(ref, map_points[i], surface, &neighbors);
      d.nearest_m[i] = s.nearest_m;
      if (s.has_surface()) d.plane_m[i] = std::abs(s.signed_m);
    }
    progress->Done(end - begin, slot);
  });
  return d;
}

// Per REF point: distance to the nearest MAP point within D (NaN beyond).
// order: VoxelOrder(ref_points, options.search.voxel_size), queried in
// that order as above.
std::vector<double> ReferenceToMap(const std::vector<Eigen::Vector3d>& ref_points,
                                   const std::vector<uint32_t>& order, const ReferenceMap& map,
                                   const MapEvalOptions& options, SearchProgress* progress) {
  const size_t n = ref_points.size();
  std::vector<double> nearest_m(n, kNoValue);
  const int chunks = static_cast<int>((n + kChunk - 1) / kChunk);
  ParallelFor(0, chunks, options.threads, [&](int chunk, int slot) {
    NeighborBuffer neighbors;
    const size_t begin = static_cast<size_t>(chunk) * kChunk;
    const size_t end = std::min(n, begin + kChunk);
    for (size_t j = begin; j < end; ++j) {
      PrefetchAhead(ref_points, order, j);
      const size_t i = order[j];
      if (map.KNearest(ref_points[i], 1, options.max_distance, &neighbors) == 1)
        nearest_m[i] = std::sqrt(neighbors.dist2[0]);
    }
    progress->Done(end - begin, slot);
  });
  return nearest_m;
}

size_t BinOf(double chainage_m, double step_m) {
  return static_cast<size_t>(std::max(0.0, std::floor(chainage_m / step_m)));
}

double MaxChainage(const std::vector<Eigen::Vector3d>& points, const ChainageAxis& axis) {
  double max_chainage = 0.0;
  for (const Eigen::Vector3d& p : points) max_chainage = std::max(max_chainage, axis.Chainage(p));
  return max_chainage;
}

// The profile's bin count, refused beyond kMaxProfileBins (before the bins
// are allocated: a tiny step would allocate them by the billion).
StatusOr<size_t> ProfileBins(double max_chainage_m, double step_m) {
  const double bins = std::floor(max_chainage_m / step_m) + 1.0;  // double: no overflow
  if (!(bins <= static_cast<double>(kMaxProfileBins))) {
    char text[256];
    std::snprintf(text, sizeof(text),
                  "profile step %g m gives %.3g bins over the reference's %.6g m along its "
                  "principal axis; at most %zu (a step of at least %.3g m)",
                  step_m, bins, max_chainage_m, kMaxProfileBins,
                  max_chainage_m / static_cast<double>(kMaxProfileBins - 1));
    return Status::InvalidInput(text);
  }
  return static_cast<size_t>(bins);
}

std::vector<MapProfileBin> Profile(const std::vector<Eigen::Vector3d>& map_points,
                                   const std::vector<Eigen::Vector3d>& ref_points,
                                   const MapPointDistances& d, const std::vector<double>& ref_nearest,
                                   const ChainageAxis& axis, size_t bins,
                                   const MapEvalOptions& options) {
  std::vector<MapProfileBin> profile(bins);
  std::vector<std::vector<double>> plane(bins);
  std::vector<size_t> covered(bins, 0);
  for (size_t b = 0; b < bins; ++b) profile[b].chainage_m = b * options.profile_step;
  for (size_t i = 0; i < ref_points.size(); ++i) {
    const size_t b = std::min(bins - 1, BinOf(axis.Chainage(ref_points[i]), options.profile_step));
    ++profile[b].ref_points;
    covered[b] += std::isnan(ref_nearest[i]) ? 0 : 1;
  }
  for (size_t i = 0; i < map_points.size(); ++i) {
    const double c = axis.Chainage(map_points[i]);
    if (c < 0.0 || c >= bins * options.profile_step) continue;  // beyond the reference
    const size_t b = BinOf(c, options.profile_step);
    ++profile[b].map_points;
    if (d.nearest_m[i] <= options.max_distance && !std::isnan(d.plane_m[i]))
      plane[b].push_back(d.plane_m[i]);
  }
  for (size_t b = 0; b < bins; ++b) {
    MapProfileBin& bin = profile[b];
    bin.completeness = bin.ref_points == 0 ? kNoValue : static_cast<double>(covered[b]) / bin.ref_points;
    bin.map_with_plane = plane[b].size();
    if (plane[b].empty()) {
      bin.rms_m = bin.median_m = bin.p95_m = kNoValue;
      continue;
    }
    const ErrorStats s = ComputeStats(std::move(plane[b]));
    bin.rms_m = s.rmse;
    bin.median_m = s.median;
    bin.p95_m = s.p95;
  }
  return profile;
}

Status CheckCloud(const std::vector<Eigen::Vector3d>& points, const char* which) {
  if (points.empty()) return Status::InvalidInput(std::string(which) + " has no points");
  size_t bad = 0;
  for (const Eigen::Vector3d& p : points) bad += p.allFinite() ? 0 : 1;
  if (bad > 0)
    return Status::InvalidInput(std::string(which) + ": " + std::to_string(bad) + " of " +
                                std::to_string(points.size()) +
                                " points have a non-finite coordinate (NaN or inf)");
  return Status::Ok();
}

// EvaluateMap of clouds in the reference's local frame (checked).
StatusOr<MapEvalResult> EvaluateLocal(const std::vector<Eigen::Vector3d>& map_points,
                                      const std::vector<Eigen::Vector3d>& ref_points,
                                      const MapEvalOptions& options,
                                      const MapEvalProgress& progress_fn) {
  if (!(options.max_distance <= kMaxDistanceVoxels * options.search.voxel_size)) {
    char text[256];
    std::snprintf(text, sizeof(text),
                  "max distance %g m is more than %g search voxels (search.voxel_size %g m): "
                  "a point without a neighbour that near would visit every voxel within it; "
                  "at most %g m",
                  options.max_distance, kMaxDistanceVoxels, options.search.voxel_size,
                  kMaxDistanceVoxels * options.search.voxel_size);
    return Status::InvalidInput(text);
  }
  const ChainageAxis axis = PrincipalAxis(ref_points);
  SearchProgress progress(progress_fn, map_points.size() + ref_points.size());
  const double D = options.max_distance;
  MapEvalResult r;
  r.map_points = map_points.size();
  r.ref_points = ref_points.size();
  r.max_distance_m = D;

  // Both clouds in voxel order: each is filled into its search structure in
  // it and queried in it (docs/map_eval.md, "Speed").
  const std::vector<uint32_t> ref_order = VoxelOrder(ref_points, options.search.voxel_size);
  const std::vector<uint32_t> map_order = VoxelOrder(map_points, options.search.voxel_size);
  MapPointDistances d;
  size_t bins = 0;
  {
    const ReferenceMap ref(ref_points, ref_order, options.search);
    if (Status s = CheckReach(ref.voxels(), ref_points); !s.ok())
      return Status::InvalidInput("the reference: " + s.message());
    // After the reach (a stray point far away is named as such), before the
    // search and the profile's bins are allocated.
    StatusOr<size_t> profile_bins = ProfileBins(MaxChainage(ref_points, axis), options.profile_step);
    if (!profile_bins.ok()) return profile_bins.status();
    bins = *profile_bins;
    d = MapToReference(map_points, map_order, ref, options, &progress);
  }  // the reference's search structure is freed before the map's is built
  std::vector<double> plane, nearest;
  double chamfer_map = 0.0;
  for (size_t i = 0; i < d.nearest_m.size(); ++i) {
    const bool inlier = d.nearest_m[i] <= D;  // false for NaN
    chamfer_map += inlier ? d.nearest_m[i] : D;
    if (!inlier) continue;
    nearest.push_back(d.nearest_m[i]);
    if (std::isnan(d.plane_m[i])) ++r.no_plane;
    else plane.push_back(d.plane_m[i]);
  }
  r.inliers = nearest.size();
  if (r.inliers == 0)
    return Status::InvalidInput("the map and the reference do not overlap: no map point lies within " +
                                std::to_string(D) + " m of a reference point (different frames or units?)");
  r.outlier_fraction = 1.0 - static_cast<double>(r.inliers) / r.map_points;
  r.accuracy = ComputeStats(std::move(plane));
  r.nearest = ComputeStats(std::move(nearest));

  std::vector<double> ref_nearest;
  {
    const ReferenceMap map(map_points, map_order, options.search);
    ref_nearest = ReferenceToMap(ref_points, ref_order, map, options, &progress);
  }
  if (progress_fn) progress_fn(1.0);
  size_t covered = 0;
  double chamfer_ref = 0.0;
  for (double e : ref_nearest) {
    covered += std::isnan(e) ? 0 : 1;
    chamfer_ref += std::isnan(e) ? D : e;
  }
  r.completeness = static_cast<double>(covered) / r.ref_points;
  r.chamfer_m = 0.5 * (chamfer_map / r.map_points + chamfer_ref / r.ref_points);

  r.axis_origin = axis.origin;
  r.axis_direction = axis.direction;
  r.profile = Profile(map_points, ref_points, d, ref_nearest, axis, bins, options);
  return r;
}

}  // namespace

ChainageAxis PrincipalAxis(const std::vector<Eigen::Vector3d>& points) {
  ChainageAxis axis;
  if (points.empty()) return axis;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) C.noalias() += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  Eigen::Vector3d dir = es.eigenvectors().col(2);
  Eigen::Index largest = 0;
  dir.cwiseAbs().maxCoeff(&largest);
  if (dir(largest) < 0.0) dir = -dir;
  double min_c = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& p : points) min_c = std::min(min_c, dir.dot(p - mean));
  axis.origin = mean + min_c * dir;
  axis.direction = dir;
  return axis;
}

StatusOr<MapEvalResult> EvaluateMap(std::vector<Eigen::Vector3d>&& map_points,
                                    std::vector<Eigen::Vector3d>&& ref_points,
                                    const MapEvalOptions& options,
                                    const MapEvalProgress& progress) {
  if (Status s = CheckCloud(map_points, "the map"); !s.ok()) return s;
  if (Status s = CheckCloud(ref_points, "the reference"); !s.ok()) return s;
  const LocalOrigin origin = ChooseLocalOrigin(ref_points);
  origin.ToLocal(&map_points);
  origin.ToLocal(&ref_points);
  StatusOr<MapEvalResult> r = EvaluateLocal(map_points, ref_points, options, progress);
  if (r.ok()) r->axis_origin = origin.ToUser(r->axis_origin);
  return r;
}

StatusOr<MapEvalResult> EvaluateMap(const std::vector<Eigen::Vector3d>& map_points,
                                    const std::vector<Eigen::Vector3d>& ref_points,
                                    const MapEvalOptions& options,
                                    const MapEvalProgress& progress) {
  if (ChooseLocalOrigin(ref_points).IsZero()) {  // no copies needed
    if (Status s = CheckCloud(map_points, "the map"); !s.ok()) return s;
    if (Status s = CheckCloud(ref_points, "the reference"); !s.ok()) return s;
    return EvaluateLocal(map_points, ref_points, options, progress);
  }
  return EvaluateMap(std::vector<Eigen::Vector3d>(map_points),
                     std::vector<Eigen::Vector3d>(ref_points), options, progress);
}

}  // namespace rvlio

#pragma once
// Map evaluation against a reference cloud (docs/map_eval.md): how far the
// map's points are from the reference surface, how much of the reference the
// map covers, and where along the reference these errors sit.
//
// Definitions (D = max_distance):
// - per MAP point: the nearest REF point's distance and the signed distance
//   to the local plane fitted to its REF neighbours
//   (constraints/reference_surface.h);
// - inlier: a MAP point whose nearest REF point lies within D; outlier
//   fraction = 1 - inliers / MAP points (outliers, or parts of the map the
//   reference did not survey);
// - accuracy: mean, RMS, median, p95 and max of |point-to-plane distance|
//   over the inliers whose reference neighbourhood is a valid plane (inliers
//   at an edge or corner of the reference count in `no_plane` instead);
//   `nearest` is the same statistics of the nearest-point distance over all
//   inliers;
// - completeness: the fraction of REF points with a MAP point within D;
// - Chamfer distance (L1, truncated at D): the mean of the two mean
//   nearest-neighbour distances, MAP -> REF and REF -> MAP, each distance
//   capped at D, so that a few far points cannot dominate it and its cost
//   stays that of a search within D: 0.5 (mean_M min(d(m, REF), D) +
//   mean_R min(d(r, MAP), D));
// - profile: chainage along REF's principal axis (the first principal
//   component through the centroid, from REF's smallest projection) in bins
//   of profile_step; per bin the accuracy of the MAP inliers and the
//   completeness of the REF points falling into it.
// Points are searched in single precision (map/reference_map.h).
#include <cstddef>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/options.h"
#include "rvlio/common/status.h"
#include "rvlio/constraints/reference_surface.h"
#include "rvlio/eval/stats.h"
#include "rvlio/map/reference_map.h"

namespace rvlio {

struct MapEvalOptions {
  double max_distance = 0.1;  // m, D
  double profile_step = 1.0;  // m, chainage bin
  int threads = 1;            // 0: all cores; results do not depend on it
  SurfaceQueryOptions surface;
  ReferenceMapOptions search;

  template <class V>
  void Visit(V& v) {
    v.Field("max_distance", max_distance, Spec().Unit("m").Positive()
        .Help("inlier / completeness / Chamfer threshold D"));
    v.Field("profile_step", profile_step, Spec().Unit("m").Positive()
        .Help("chainage bin of the profile along the reference's principal axis"));
    v.Field("threads", threads, Spec().Range(0, 256).Help("0: all cores"));
    v.Section("surface", surface);
    v.Section("search", search);
  }
  Status Validate() { return ValidateFields(*this, "map_eval"); }
};

struct MapProfileBin {
  double chainage_m = 0.0;      // start of the bin
  size_t map_points = 0;        // MAP points in the bin
  size_t map_with_plane = 0;    // of which inliers with a valid plane (the accuracy's sample)
  double rms_m = 0.0;           // |point-to-plane| over those; NaN when none
  double median_m = 0.0;
  double p95_m = 0.0;
  size_t ref_points = 0;        // REF points in the bin
  double completeness = 0.0;    // their fraction with a MAP point within D; NaN when none
};

struct MapEvalResult {
  size_t map_points = 0, ref_points = 0;
  size_t inliers = 0;    // MAP points with a REF point within D
  size_t no_plane = 0;   // inliers without a valid reference plane
  ErrorStats accuracy;   // |point-to-plane| (m) over inliers with a plane (p95 too)
  ErrorStats nearest;    // nearest-point distance (m) over the inliers
  double completeness = 0.0;
  double chamfer_m = 0.0;
  double outlier_fraction = 0.0;
  double max_distance_m = 0.0;  // D used
  Eigen::Vector3d axis_origin = Eigen::Vector3d::Zero();     // REF point of chainage 0
  Eigen::Vector3d axis_direction = Eigen::Vector3d::UnitX();  // unit
  std::vector<MapProfileBin> profile;
};

// Principal axis of a cloud (centroid, unit direction of largest spread,
// sign: largest component positive) and the chainage of each point along
// it, shifted so that the smallest is 0.
struct ChainageAxis {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();
  double Chainage(const Eigen::Vector3d& p) const { return direction.dot(p - origin); }
};
ChainageAxis PrincipalAxis(const std::vector<Eigen::Vector3d>& points);

// The profile holds at most this many bins: a profile_step that gives more
// over the reference's extent along its axis is refused (a 1 m step covers
// 100 km; the --json output of that many bins is about 20 MB).
inline constexpr size_t kMaxProfileBins = 100000;

// D is at most this many search voxels (search.voxel_size; 1 m at the
// default 0.1 m). A point with a neighbour within a few voxels costs the same
// for any D (VoxelMap::KNearest ends after a few shells), but one without
// (an unmapped stretch of the reference, a stray map point) visits every
// voxel within D: (2 D / voxel_size + 3)^3 of them, 12 167 at this bound.
inline constexpr double kMaxDistanceVoxels = 10.0;

// Called with the share of the nearest-point searches done (0..1), from the
// calling thread, after blocks of 4096 points, and with 1 when all are done.
using MapEvalProgress = std::function<void(double fraction)>;

// Evaluates map_points against ref_points (same frame, m). Both are moved
// into the reference's local frame first (ChooseLocalOrigin(ref_points),
// math/local_origin.h), so clouds in a national grid (UTM) are searched as
// precisely as clouds near zero; axis_origin is given back in their frame.
// InvalidInput (message without file names; the caller adds them) for an
// empty cloud, a non-finite point, a max_distance beyond kMaxDistanceVoxels
// search voxels, a profile_step giving more than kMaxProfileBins bins, a
// reference point beyond its search structure's reach from the local origin
// (CheckReach: 104.8 km along an axis at 0.1 m voxels), or clouds that do not
// overlap (no MAP point within D of REF).
StatusOr<MapEvalResult> EvaluateMap(const std::vector<Eigen::Vector3d>& map_points,
                                    const std::vector<Eigen::Vector3d>& ref_points,
                                    const MapEvalOptions& options,
                                    const MapEvalProgress& progress = nullptr);
// The same, moving the clouds into the local frame in place (no copies: for
// clouds read only for this).
StatusOr<MapEvalResult> EvaluateMap(std::vector<Eigen::Vector3d>&& map_points,
                                    std::vector<Eigen::Vector3d>&& ref_points,
                                    const MapEvalOptions& options,
                                    const MapEvalProgress& progress = nullptr);

}  // namespace rvlio

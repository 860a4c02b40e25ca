#pragma once
// Distance of a point to the surface of a fixed reference cloud
// (map/reference_map.h; docs/map_eval.md): the nearest reference point, and
// the signed distance to the local plane fitted (plane_fit.h, the project's
// one plane fit and validity test) to the reference's k nearest points.
//
// A query has a surface when all k neighbours lie within search_radius of it
// and their plane passes the validity test; otherwise signed_m is NaN (no
// reference surface there: outside the surveyed part, a hole, an edge or
// clutter). nearest_m is NaN only when no reference point lies within
// search_radius.
//
// Sign: the plane's normal has no natural sign. With a view point (the
// sensor position the query point was seen from, or any point on the open
// side of the surface) the normal is oriented towards it, so a positive
// distance lies on the view point's side (into the free space: a deposit or
// a convergence of a tunnel wall) and a negative one behind the surface.
// Without a view point the normal is oriented towards the query point, so
// signed_m = |distance| >= 0.
#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "rvlio/common/options.h"
#include "rvlio/constraints/plane_fit.h"
#include "rvlio/map/reference_map.h"

namespace rvlio {

struct SurfaceQueryOptions {
  int num_neighbors = 8;        // k reference points per plane
  double search_radius = 0.5;   // m, all k must lie this close to the query
  // Validity test of the plane (plane_fit.h); max_plane_distance and
  // point_noise matter for a survey's millimetre noise as for a LiDAR map's
  // centimetre noise, the planarity ratios reject edges and corners.
  double planarity_min_ratio = 0.1;
  double planarity_max_ratio = 0.1;
  double max_plane_distance = 0.1;  // m

  PlaneThresholds Thresholds() const {
    PlaneThresholds t;
    t.planarity_min_ratio = planarity_min_ratio;
    t.planarity_max_ratio = planarity_max_ratio;
    t.max_plane_distance = max_plane_distance;
    t.max_normal_std = 0.0;  // test off
    return t;
  }

  template <class V>
  void Visit(V& v) {
    v.Field("num_neighbors", num_neighbors, Spec().Range(3, kMaxNeighbors)
        .Help("reference points per local plane"));
    v.Field("search_radius", search_radius, Spec().Unit("m").Positive()
        .Help("every neighbour of a plane lies within this distance of the query point"));
    v.Field("planarity_min_ratio", planarity_min_ratio, Spec().Range(0.0, 1.0)
        .Help("reject line-like reference neighbourhoods"));
    v.Field("planarity_max_ratio", planarity_max_ratio, Spec().Range(0.0, 1.0)
        .Help("reject non-flat reference neighbourhoods"));
    v.Field("max_plane_distance", max_plane_distance, Spec().Unit("m").Positive()
        .Help("every neighbour lies this close to the fitted plane"));
  }
};

struct SurfaceDistance {
  double nearest_m = std::numeric_limits<double>::quiet_NaN();  // to the nearest reference point
  double signed_m = std::numeric_limits<double>::quiet_NaN();   // to the local plane (see above)
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // plane's unit normal (oriented), reference frame
  int num_neighbors = 0;                              // reference points found within search_radius
  PlaneStatus status = PlaneStatus::kTooFewPoints;    // kTooFewPoints also when < k within the radius

  bool has_surface() const { return status == PlaneStatus::kValid; }
};

// One query (reference frame, m). `neighbors` is scratch space (reused
// across queries: no allocation); view_ref orients the normal (see above).
SurfaceDistance QueryReferenceSurface(const ReferenceMap& reference, const Eigen::Vector3d& q_ref,
                                      const SurfaceQueryOptions& options,
                                      NeighborBuffer* neighbors,
                                      const Eigen::Vector3d* view_ref = nullptr);

}  // namespace rvlio

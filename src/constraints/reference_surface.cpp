#include "rvlio/constraints/reference_surface.h"

#include "rvlio/common/check.h"

namespace rvlio {

SurfaceDistance QueryReferenceSurface(const ReferenceMap& reference, const Eigen::Vector3d& q_ref,
                                      const SurfaceQueryOptions& options,
                                      NeighborBuffer* neighbors, const Eigen::Vector3d* view_ref) {
  RVLIO_CHECK(neighbors != nullptr);
  SurfaceDistance d;
  const int k = options.num_neighbors;
  d.num_neighbors = reference.KNearest(q_ref, k, options.search_radius, neighbors);
  if (d.num_neighbors == 0) return d;
  d.nearest_m = std::sqrt(neighbors->dist2[0]);
  if (d.num_neighbors < k) return d;  // status kTooFewPoints
  const LocalPlane plane = FitLocalPlane(*neighbors, options.Thresholds());
  d.status = plane.status;
  if (!plane.valid()) return d;
  const Eigen::Vector3d towards = view_ref != nullptr ? *view_ref : q_ref;
  d.normal = plane.normal.dot(towards - plane.centroid) < 0.0 ? -plane.normal : plane.normal;
  d.signed_m = d.normal.dot(q_ref - plane.centroid);
  return d;
}

}  // namespace rvlio

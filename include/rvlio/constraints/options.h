#pragma once
// Point-to-plane association (docs/design.md "The shared measurement model").
#include "rvlio/common/options.h"

namespace rvlio {

struct ConstraintOptions {
  int num_neighbors = 5;                // k nearest map points per scan point
  double max_neighbor_distance = 2.0;   // m, farthest neighbour accepted
  double max_plane_distance = 0.1;      // m, every neighbour must be this close to the plane
  double planarity_min_ratio = 0.1;     // lambda_mid / lambda_max must exceed this (not a line)
  double planarity_max_ratio = 0.1;     // lambda_min / lambda_mid must stay below this (flat)
  double max_residual = 1.0;            // m, |r| above this is an outlier at association time
  double lidar_noise = 0.03;            // m, std of one point-to-plane residual
  double max_normal_std_deg = 0.0;      // deg, reject planes whose normal is this uncertain (0: off)
  double reuse_distance = 0.05;         // m, IESKF: later iterations of one scan keep a point's plane while it moved less (0: search every iteration)
  int threads = 1;                      // threads of one scan's association in `rvlio run` (IESKF, smoother); 0: all cores

  template <class V>
  void Visit(V& v) {
    v.Field("num_neighbors", num_neighbors, Spec().Range(3, 20));
    v.Field("max_neighbor_distance", max_neighbor_distance, Spec().Unit("m").Positive());
    v.Field("max_plane_distance", max_plane_distance, Spec().Unit("m").Positive());
    v.Field("planarity_min_ratio", planarity_min_ratio, Spec().Range(0.0, 1.0)
                                                         .Help("reject line-like neighbourhoods"));
    v.Field("planarity_max_ratio", planarity_max_ratio, Spec().Range(0.0, 1.0)
                                                         .Help("reject non-flat neighbourhoods"));
    v.Field("max_residual", max_residual, Spec().Unit("m").Positive());
    v.Field("lidar_noise", lidar_noise, Spec().Unit("m").Positive().Help("residual std (R = sigma^2)"));
    v.Field("max_normal_std_deg", max_normal_std_deg, Spec().Unit("deg").Range(0.0, 90.0)
        .Help("reject planes whose normal's predicted tilt std (from lidar_noise) exceeds this; 0: off"));
    v.Field("reuse_distance", reuse_distance, Spec().Unit("m").Range(0.0, 1.0)
        .Help("IESKF iterations of one scan reuse a point's plane while it moved less than this; 0: search every iteration"));
    v.Field("threads", threads, Spec().Range(0, 256)
        .Help("threads sharing one scan's association in `rvlio run` (IESKF and smoother); the constraints are the same for any count; 0: all cores"));
  }
  Status Validate() { return ValidateFields(*this, "constraints"); }
};

}  // namespace rvlio

#pragma once
// Incremental voxel-hash map.
#include <string>

#include "rvlio/common/options.h"

namespace rvlio {

struct MapOptions {
  double voxel_size = 0.5;          // m, edge of one hash voxel of the working map (chosen by measurement, README)
  int max_points_per_voxel = 20;    // points kept per voxel
  double min_point_distance = 0.1;  // m, a new point closer than this to a stored one is skipped
  double working_radius = 60.0;     // m, voxels farther from the sensor are removed
  double output_resolution = 0.2;   // m, voxel size of the full map written to map.pcd
  // k-nearest search of the map: "exact" (every voxel that can hold a point
  // within the neighbour distance) or "nearby" (only the query's voxel and
  // the 26 around it, as iVox's nearby search: neighbours farther than one
  // voxel edge from the query's voxel are not found; docs/speed.md).
  std::string neighbor_search = "exact";
  // Online extrinsic estimation only (ieskf/smoother.estimate_extrinsics): the
  // working map is rebuilt from the scans of the last reanchor_window seconds
  // with the current extrinsic once the estimate has moved more than
  // reanchor_rotation or reanchor_translation since the map was last built
  // (docs/extrinsics.md "Map re-anchoring"). 0 s = never (the default).
  double reanchor_window = 0.0;        // s
  double reanchor_rotation = 0.2;      // deg
  double reanchor_translation = 0.01;  // m

  template <class V>
  void Visit(V& v) {
    v.Field("voxel_size", voxel_size, Spec().Unit("m").Range(0.05, 20.0));
    v.Field("max_points_per_voxel", max_points_per_voxel, Spec().Range(1, 1000));
    v.Field("min_point_distance", min_point_distance, Spec().Unit("m").Range(0.0, 5.0));
    v.Field("working_radius", working_radius, Spec().Unit("m").Range(1.0, 10000.0));
    v.Field("output_resolution", output_resolution, Spec().Unit("m").Range(0.01, 10.0));
    v.Field("neighbor_search", neighbor_search, Spec().Choices({"exact", "nearby"}));
    v.Field("reanchor_window", reanchor_window, Spec().Unit("s").Range(0.0, 3600.0));
    v.Field("reanchor_rotation", reanchor_rotation, Spec().Unit("deg").Range(0.0, 180.0));
    v.Field("reanchor_translation", reanchor_translation, Spec().Unit("m").Range(0.0, 10.0));
  }
  Status Validate() { return ValidateFields(*this, "map"); }
};

}  // namespace rvlio

#pragma once
// Incremental voxel-hash map.
#include "rvlio/common/options.h"

namespace rvlio {

struct MapOptions {
  double voxel_size = 0.5;          // m, edge of one hash voxel of the working map (chosen by measurement, README)
  int max_points_per_voxel = 20;    // points kept per voxel
  double min_point_distance = 0.1;  // m, a new point closer than this to a stored one is skipped
  double working_radius = 60.0;     // m, voxels farther from the sensor are removed
  double output_resolution = 0.2;   // m, voxel size of the full map written to map.pcd

  template <class V>
  void Visit(V& v) {
    v.Field("voxel_size", voxel_size, Spec().Unit("m").Range(0.05, 20.0));
    v.Field("max_points_per_voxel", max_points_per_voxel, Spec().Range(1, 1000));
    v.Field("min_point_distance", min_point_distance, Spec().Unit("m").Range(0.0, 5.0));
    v.Field("working_radius", working_radius, Spec().Unit("m").Range(1.0, 10000.0));
    v.Field("output_resolution", output_resolution, Spec().Unit("m").Range(0.01, 10.0));
  }
  Status Validate() { return ValidateFields(*this, "map"); }
};

}  // namespace rvlio

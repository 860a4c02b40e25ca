#pragma once
// What a run writes besides its fixed outputs (config section `output`) and the
// coordinate reference system of its map frame (config section `survey`):
// map.las beside map.pcd in `run`, `refine` and `merge` (docs/outputs.md "map.las").
// trajectory_imu.tum, the pose at IMU rate, in `run`, `refine` and `merge`
// (docs/outputs.md "trajectory_imu.tum").
// Plain option structs of the Configuration (config/configuration.h); the CRS is
// resolved (PROJ, formats/crs.h) in the I/O layer only.
#include <string>

#include "rvlio/common/options.h"

namespace rvlio {

struct OutputOptions {
  bool las = false;  // also write map.las (LAS 1.4, point format 6) beside map.pcd
  bool imu_trajectory = false;  // also write trajectory_imu.tum (a pose at every IMU sample)

  template <class V>
  void Visit(V& v) {
    v.Field("las", las,
            Spec().Help("also write map.las (ASPRS LAS 1.4, point data record format 6, 1 mm "
                        "coordinates) beside map.pcd in run, refine and merge (docs/outputs.md)"));
    v.Field("imu_trajectory", imu_trajectory,
            Spec().Help("also write trajectory_imu.tum in run, refine and merge: the pose at every "
                        "IMU sample between the first and the last scan's, as trajectory.tum "
                        "(docs/outputs.md)"));
  }
  Status Validate() { return ValidateFields(*this, "output"); }
};

// "local": the map frame has no known coordinate reference system (map.las
// then carries none).
inline constexpr const char* kLocalCrs = "local";

struct SurveyOptions {
  // EPSG:CODE (e.g. EPSG:25832), a PROJ string, OGC WKT, or local.
  std::string crs = kLocalCrs;

  template <class V>
  void Visit(V& v) {
    v.Field("crs", crs,
            Spec().Help("coordinate reference system of the map frame: local (none), EPSG:CODE, "
                        "a PROJ string or WKT; written into map.las as OGC WKT"));
  }
  Status Validate() {
    if (crs.empty())
      return Status::InvalidInput("survey.crs is empty (local for none, or e.g. EPSG:25832)");
    return ValidateFields(*this, "survey");
  }
};

}  // namespace rvlio

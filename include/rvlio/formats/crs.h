#pragma once
// Coordinate reference systems through PROJ (Debian libproj-dev, linked
// privately into rvlio_io): the `survey.crs` string resolved to OGC WKT for
// map.las (docs/outputs.md "map.las"), and latitude / longitude / ellipsoidal
// height carried into that CRS (for a GNSS position).
//
// A CRS string is what PROJ's proj_create accepts: an authority code
// ("EPSG:25832", "EPSG:25832+7837" for a compound one), a PROJ string
// ("+proj=utm +zone=32 +ellps=GRS80 +units=m +type=crs") or WKT. "local"
// means none. The map is in metres, so a geographic (degree) CRS is refused.
// PROJ's own messages are not printed; each error is one line naming the
// string.
#include <memory>
#include <string>

#include <Eigen/Core>

#include "rvlio/common/status.h"

namespace rvlio {

struct Crs {
  std::string given;  // the string as the user wrote it
  std::string name;   // PROJ's name of it, e.g. "ETRS89 / UTM zone 32N"
  std::string wkt;    // OGC WKT 1 (the GDAL dialect LAS 1.4 readers expect; WKT 2 when
                      // the CRS has no WKT 1 form)
};

// True for "local" (no CRS).
bool IsLocalCrs(const std::string& crs);

// InvalidInput naming `crs` when PROJ does not know it, it is not a CRS, or it
// is geographic (degrees). `crs` must not be local.
StatusOr<Crs> ResolveCrs(const std::string& crs);

// Geodetic latitude, longitude (degrees) and ellipsoidal height (m) on WGS 84
// (EPSG:4979) into the coordinates of a target CRS (for a projected CRS:
// easting, northing, m; the height passes through unless the target has a
// vertical datum that PROJ can reach).
class GeodeticToCrs {
 public:
  static StatusOr<GeodeticToCrs> Create(const std::string& target_crs);
  ~GeodeticToCrs();
  GeodeticToCrs(GeodeticToCrs&&) noexcept;
  GeodeticToCrs& operator=(GeodeticToCrs&&) noexcept;

  // InvalidInput when PROJ cannot transform the point (outside the CRS's area
  // of use, non-finite input).
  StatusOr<Eigen::Vector3d> Transform(double latitude_deg, double longitude_deg,
                                      double height_m) const;
  // The inverse: CRS coordinates to (latitude_deg, longitude_deg, height_m)
  // (the simulator's GNSS fixes).
  StatusOr<Eigen::Vector3d> Inverse(const Eigen::Vector3d& p_crs) const;

 private:
  struct Impl;
  explicit GeodeticToCrs(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rvlio

#pragma once
// map.las: an rvlio map as ASPRS LAS 1.4 (formats/las_writer.h; every field
// and how each PCD field maps is in docs/outputs.md "map.las"). Written by
// run, refine and merge beside map.pcd when output.las is set, and by
// `rvlio export` from any map PCD, streamed in bounded memory.
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/formats/las_writer.h"
#include "rvlio/map/map_cloud.h"
#include "rvlio/outputs/output_options.h"

namespace rvlio {

// The OGC WKT of a CRS string (formats/crs.h); "" for local. InvalidInput
// naming the string for an unknown or geographic CRS.
StatusOr<std::string> CrsWkt(const std::string& crs);

// What run, refine and merge write besides map.pcd: `enabled` from
// output.las, the WKT of survey.crs. Resolved before the work starts, so an
// unknown CRS is an error before anything is read.
struct MapLasRequest {
  bool enabled = false;
  std::string crs_wkt;  // "" for local
};
StatusOr<MapLasRequest> MapLasRequestOf(const OutputOptions& output, const SurveyOptions& survey);

// map.las of the output map (the map.pcd frame) with its attributes and
// deviation_m (one per point, NaN allowed) when it is not null, atomically:
// the coordinates as map.pcd stores them (float32 below 8192 m,
// MapNeedsFloat64) and every field where `rvlio export` of the map.pcd of
// the same map puts it (the same bytes), the intensity range from the
// largest intensity. Built
// chunk_points at a time (the memory beyond the map's).
Status WriteMapLas(const std::string& path, const MapCloud& map,
                   const std::vector<double>* deviation_m, const std::string& crs_wkt,
                   size_t chunk_points = size_t{1} << 16);

struct LasExportOptions {
  std::string crs = kLocalCrs;  // survey.crs syntax
  // The sensor's intensity range (levels: 256 for 8 bit); LAS intensity =
  // value x 65536 / range. 0: from the map's largest intensity (a first pass
  // over the file): 1 when it is at most 1 (normalized), else 256, 65536 or
  // the next integer above it.
  double intensity_range = 0.0;
  size_t chunk_points = 1 << 16;  // points read and written per step (the memory bound)
  std::function<bool()> stop;     // polled per chunk: true ends the export, nothing written
};

struct LasExportResult {
  LasWriteStats stats;
  std::string intensity_field;  // the PCD field written as LAS intensity ("" if none)
  double intensity_range = 0.0;
  std::string time_field;       // ... as GPS time
  std::string ring_field;       // ... as User Data
  std::vector<std::string> extra_fields;  // ... as extra bytes, in order
  std::vector<std::string> warnings;      // clamped intensities, saturated rings
  bool stopped = false;                   // `stop` ended it: nothing was written
};

// `rvlio export`: a map PCD (DATA ascii or binary) into LAS. InvalidInput
// naming the file for a missing, corrupt or truncated map, an unknown CRS, an
// output that is the input or is not .las; IoError for an output that cannot
// be written. Nothing is left at `las_path` on failure.
StatusOr<LasExportResult> ExportPointCloudToLas(const std::string& pcd_path,
                                                const std::string& las_path,
                                                const LasExportOptions& options);

}  // namespace rvlio

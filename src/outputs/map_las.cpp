#include "rvlio/outputs/map_las.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <set>

#include "rvlio/formats/crs.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/outputs/map_fields.h"
#include "rvlio/outputs/run_outputs.h"

namespace rvlio {
namespace {

// The PCD fields that become LAS's own fields (docs/outputs.md "map.las");
// every other kept field becomes extra bytes of its own type.
constexpr const char* kIntensityFields[] = {"intensity", "reflectivity"};
constexpr const char* kTimeFields[] = {"time", "timestamp", "t"};  // F8 only: UNIX seconds
constexpr const char* kRingFields[] = {"ring"};
constexpr const char* kScanIndexField = "scan_index";  // Point Source ID, and extra bytes
constexpr const char* kDeviationField = "deviation_m";

struct FieldRoles {
  int intensity = -1, time = -1, ring = -1, scan_index = -1;
  std::vector<int> extra;  // indices into the stream's fields
};

int FindField(const std::vector<PointCloudStreamField>& fields, const char* name,
              bool need_f8 = false) {
  for (size_t i = 0; i < fields.size(); ++i)
    if (fields[i].name == name && (!need_f8 || (fields[i].type == 'F' && fields[i].size == 8)))
      return static_cast<int>(i);
  return -1;
}

template <size_t N>
int FirstOf(const std::vector<PointCloudStreamField>& fields, const char* const (&names)[N],
            bool need_f8 = false) {
  for (const char* name : names)
    if (int i = FindField(fields, name, need_f8); i >= 0) return i;
  return -1;
}

FieldRoles AssignRoles(const std::vector<PointCloudStreamField>& fields) {
  FieldRoles r;
  r.intensity = FirstOf(fields, kIntensityFields);
  // A time in F4 or an integer type cannot hold absolute seconds: kept as extra bytes.
  r.time = FirstOf(fields, kTimeFields, true);
  r.ring = FirstOf(fields, kRingFields);
  r.scan_index = FindField(fields, kScanIndexField);
  for (size_t i = 0; i < fields.size(); ++i) {
    const int k = static_cast<int>(i);
    if (k != r.intensity && k != r.time && k != r.ring) r.extra.push_back(k);
  }
  return r;
}

LasScalar ScalarOf(const PointCloudStreamField& f) {
  if (f.type == 'F') return f.size == 8 ? LasScalar::kDouble : LasScalar::kFloat;
  const bool is_signed = f.type == 'I';
  switch (f.size) {
    case 1: return is_signed ? LasScalar::kInt8 : LasScalar::kUint8;
    case 2: return is_signed ? LasScalar::kInt16 : LasScalar::kUint16;
    case 4: return is_signed ? LasScalar::kInt32 : LasScalar::kUint32;
    default: return is_signed ? LasScalar::kInt64 : LasScalar::kUint64;
  }
}

std::string DescriptionOf(const std::string& name) {
  if (name == kDeviationField) return "to the reference surface, m";
  if (name == "scan_index") return "index of the scan of the point";
  return "map.pcd field " + name.substr(0, 17);
}

// The sensor's intensity range from the largest value (LasExportOptions).
double RangeOfLargest(double largest) {
  if (!(largest > 1.0)) return 1.0;
  if (largest < 256.0) return 256.0;
  if (largest < 65536.0) return 65536.0;
  return std::floor(largest) + 1.0;
}

// The largest value of field `k` over the whole file (a first pass).
StatusOr<double> LargestValue(const std::string& path, int k, size_t chunk_points) {
  PointCloudStream stream;
  if (Status s = stream.Open(path); !s.ok()) return s;
  PointCloudChunk chunk;
  double largest = 0.0;
  for (;;) {
    StatusOr<size_t> n = stream.Read(chunk_points, &chunk);
    if (!n.ok()) return n.status();
    if (*n == 0) return largest;
    for (double v : chunk.fields[k])
      if (std::isfinite(v)) largest = std::max(largest, v);
  }
}

bool EndsWithLas(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  std::string lower(ext.size(), ' ');
  std::transform(ext.begin(), ext.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return lower == ".las";
}

// A PCD field name that LAS extra bytes cannot hold, or a name given twice.
Status CheckFieldNames(const std::string& path, const std::vector<PointCloudStreamField>& fields) {
  std::set<std::string> seen;
  for (const PointCloudStreamField& f : fields) {
    if (f.name.size() > 32)
      return Status::InvalidInput(path + ": field '" + f.name.substr(0, 40) +
                                  "...' has a longer name than LAS extra bytes hold (32 characters)");
    if (!seen.insert(f.name).second)
      return Status::InvalidInput(path + ": field " + f.name + " appears twice");
  }
  return Status::Ok();
}

Status CheckExportPaths(const std::string& pcd_path, const std::string& las_path) {
  if (!EndsWithLas(las_path))
    return Status::InvalidInput(las_path + ": the output must be a .las file (rvlio writes "
                                           "uncompressed LAS; laszip makes a .laz of it)");
  std::error_code ec;
  if (std::filesystem::is_directory(las_path, ec))
    return Status::InvalidInput(las_path + ": is a directory; give the .las file to write");
  if (std::filesystem::exists(las_path, ec) && std::filesystem::equivalent(pcd_path, las_path, ec))
    return Status::InvalidInput(las_path + ": is the input map; give another output file");
  return Status::Ok();
}

void AddWarnings(const LasWriteStats& stats, const std::string& path,
                 std::vector<std::string>* warnings) {
  if (stats.intensity_clamped > 0)
    warnings->push_back(path + ": " + std::to_string(stats.intensity_clamped) +
                        " intensities outside the range were clamped to 0..65535 "
                        "(--intensity-range sets the sensor's range)");
  if (stats.ring_saturated > 0)
    warnings->push_back(path + ": " + std::to_string(stats.ring_saturated) +
                        " rings outside 0..255 were stored as 0 or 255 (LAS User Data is 8 bits)");
}

// The writer's options for a map of these fields (x y z apart) and the
// names of what goes where; intensity_range > 0 (the sensor's levels).
LasWriterOptions PlanLas(const std::vector<PointCloudStreamField>& fields, const FieldRoles& roles,
                         double intensity_range, const std::string& crs_wkt,
                         LasExportResult* result) {
  LasWriterOptions w;
  w.crs_wkt = crs_wkt;
  if (roles.intensity >= 0) {
    result->intensity_field = fields[roles.intensity].name;
    result->intensity_range = intensity_range;
    w.intensity_scale = 65536.0 / intensity_range;
    w.intensity_source = "map.pcd field " + result->intensity_field + " (range " +
                         std::to_string(static_cast<int64_t>(intensity_range)) + ")";
  }
  if (roles.time >= 0) result->time_field = fields[roles.time].name;
  if (roles.ring >= 0) result->ring_field = fields[roles.ring].name;
  w.has_time = roles.time >= 0;
  w.has_ring = roles.ring >= 0;
  w.has_point_source = roles.scan_index >= 0;
  for (int k : roles.extra) {
    w.extra_fields.push_back({fields[k].name, ScalarOf(fields[k]), DescriptionOf(fields[k].name)});
    result->extra_fields.push_back(fields[k].name);
  }
  return w;
}

// The first n points of a chunk through the writer, each field in its role.
Status WriteChunk(const PointCloudChunk& chunk, size_t n, const FieldRoles& roles,
                  LasWriter* writer) {
  std::vector<double> extra(roles.extra.size());
  LasPoint point;
  point.extra = extra.data();
  for (size_t i = 0; i < n; ++i) {
    point.p_m = chunk.points[i];
    if (roles.intensity >= 0) point.intensity = chunk.fields[roles.intensity][i];
    if (roles.time >= 0) point.unix_time_s = chunk.fields[roles.time][i];
    if (roles.ring >= 0) {
      const double ring = chunk.fields[roles.ring][i];
      point.ring = std::isfinite(ring) ? static_cast<int>(std::clamp(ring, -1.0, 256.0)) : -1;
    }
    if (roles.scan_index >= 0) {
      const double index = chunk.fields[roles.scan_index][i];
      point.scan_index = std::isfinite(index) && index >= 0.0 && index < 1.8e19
                             ? static_cast<uint64_t>(index) : 0;
    }
    for (size_t k = 0; k < roles.extra.size(); ++k) extra[k] = chunk.fields[roles.extra[k]][i];
    if (Status s = writer->Write(point); !s.ok()) return s;
  }
  return Status::Ok();
}

}  // namespace

StatusOr<std::string> CrsWkt(const std::string& crs) {
  if (IsLocalCrs(crs)) return std::string();
  StatusOr<Crs> resolved = ResolveCrs(crs);
  if (!resolved.ok()) return resolved.status();
  return resolved->wkt;
}

StatusOr<MapLasRequest> MapLasRequestOf(const OutputOptions& output, const SurveyOptions& survey) {
  MapLasRequest r;
  r.enabled = output.las;
  StatusOr<std::string> wkt = CrsWkt(survey.crs);  // checked even without output.las
  if (!wkt.ok()) return wkt.status();
  r.crs_wkt = std::move(*wkt);
  return r;
}

Status WriteMapLas(const std::string& path, const MapCloud& map,
                   const std::vector<double>* deviation_m, const std::string& crs_wkt,
                   size_t chunk_points) {
  // The coordinates and fields as map.pcd has them (x y z in float32 below
  // 8192 m: a step of 1 mm at most), so that `rvlio export` of that file
  // writes the same bytes.
  const bool float32_xyz = !MapNeedsFloat64(map.p);
  std::vector<PointCloudStreamField> fields;
  const std::vector<MapFieldSpec> specs = MapAttributeFields(map, deviation_m != nullptr);
  for (const MapFieldSpec& f : specs) fields.push_back({f.name, f.type, f.size});
  const FieldRoles roles = AssignRoles(fields);
  double largest_intensity = 0.0;
  for (float v : map.intensity)
    if (std::isfinite(v)) largest_intensity = std::max(largest_intensity, static_cast<double>(v));
  LasExportResult names;
  LasWriter writer;
  if (Status s = writer.Open(path, PlanLas(fields, roles, RangeOfLargest(largest_intensity),
                                           crs_wkt, &names));
      !s.ok())
    return s;
  PointCloudChunk chunk;
  chunk.fields.resize(specs.size());
  for (size_t first = 0; first < map.size(); first += chunk_points) {
    const size_t n = std::min(chunk_points, map.size() - first);
    chunk.points.assign(map.p.begin() + first, map.p.begin() + first + n);
    if (float32_xyz) RoundToFloat32(&chunk.points);
    for (size_t k = 0; k < specs.size(); ++k) {
      chunk.fields[k].resize(n);
      for (size_t i = 0; i < n; ++i)
        chunk.fields[k][i] = MapFieldValue(specs[k].field, map, deviation_m, first + i);
    }
    if (Status s = WriteChunk(chunk, n, roles, &writer); !s.ok()) return s;
  }
  return writer.Commit();
}

StatusOr<LasExportResult> ExportPointCloudToLas(const std::string& pcd_path,
                                                const std::string& las_path,
                                                const LasExportOptions& options) {
  if (Status s = CheckExportPaths(pcd_path, las_path); !s.ok()) return s;
  StatusOr<std::string> wkt = CrsWkt(options.crs);
  if (!wkt.ok()) return wkt.status();
  PointCloudStream stream;
  if (Status s = stream.Open(pcd_path); !s.ok()) return s;
  const std::vector<PointCloudStreamField>& fields = stream.fields();
  if (Status s = CheckFieldNames(pcd_path, fields); !s.ok()) return s;
  const FieldRoles roles = AssignRoles(fields);
  LasExportResult result;
  double range = options.intensity_range;
  if (roles.intensity >= 0 && range <= 0.0) {
    StatusOr<double> largest = LargestValue(pcd_path, roles.intensity, options.chunk_points);
    if (!largest.ok()) return largest.status();
    range = RangeOfLargest(*largest);
  }
  LasWriter writer;
  if (Status s = writer.Open(las_path, PlanLas(fields, roles, range, *wkt, &result)); !s.ok())
    return s;
  PointCloudChunk chunk;
  for (;;) {
    if (options.stop && options.stop()) {
      result.stopped = true;
      return result;  // the writer discards its temporary file
    }
    StatusOr<size_t> n = stream.Read(options.chunk_points, &chunk);
    if (!n.ok()) return n.status();
    if (*n == 0) break;
    if (Status s = WriteChunk(chunk, *n, roles, &writer); !s.ok()) return s;
  }
  if (Status s = writer.Commit(); !s.ok()) return s;
  result.stats = writer.stats();
  AddWarnings(result.stats, las_path, &result.warnings);
  return result;
}

}  // namespace rvlio

#include "rvlio/outputs/run_outputs.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "rvlio/common/check.h"
#include "rvlio/common/median.h"
#include "rvlio/common/text.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/math/local_origin.h"
#include "rvlio/outputs/map_fields.h"
#include "rvlio/outputs/scan_columns.h"

namespace rvlio {
namespace {

// The header of a binary PCD (v0.7) of n unorganized points with the fields
// x y z (float32, or float64 when xyz_bytes is 8) and then `attributes`:
// byte for byte the header PCL's PCDWriter::writeBinary writes for such a
// cloud (tests MapPcdIsWhatPclWritesAndReads, FarMapPcdIsFloat64AndWhatPclWrites,
// MapPcdWithAttributesIsWhatPclWritesAndReads), also for n = 0, which PCL
// refuses to write.
std::string PcdBinaryHeader(size_t n, int xyz_bytes, const std::vector<MapFieldSpec>& attributes) {
  const std::string count = std::to_string(n);
  const std::string xyz_size = std::to_string(xyz_bytes);
  std::string names = "x y z", sizes = xyz_size + " " + xyz_size + " " + xyz_size,
              types = "F F F", counts = "1 1 1";
  for (const MapFieldSpec& f : attributes) {
    names += std::string(" ") + f.name;
    sizes += " " + std::to_string(f.size);
    types += std::string(" ") + f.type;
    counts += " 1";
  }
  return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " + names + "\nSIZE " +
         sizes + "\nTYPE " + types + "\nCOUNT " + counts + "\nWIDTH " + count +
         "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + count + "\nDATA binary\n";
}

constexpr size_t kPcdBlockPoints = 1 << 15;  // points per Append of map.pcd

template <typename T>
void AppendValue(T value, std::string* block) {
  block->append(reinterpret_cast<const char*>(&value), sizeof(T));
}

// Point i's record: x y z as float32 or float64 (xyz_bytes), then its attributes.
void AppendPcdRecord(const MapCloud& map, const std::vector<double>* deviation_m, size_t i,
                     int xyz_bytes, const std::vector<MapFieldSpec>& attributes,
                     std::string* block) {
  const Eigen::Vector3d& p = map.p[i];
  for (int k = 0; k < 3; ++k) {
    if (xyz_bytes == 8) AppendValue<double>(p[k], block);
    else AppendValue<float>(static_cast<float>(p[k]), block);
  }
  for (const MapFieldSpec& f : attributes) {
    switch (f.field) {
      case MapField::kIntensity: AppendValue<float>(map.intensity[i], block); break;
      case MapField::kTime: AppendValue<double>(MapTimeSeconds(map.t_ns[i]), block); break;
      case MapField::kRing: AppendValue<uint16_t>(map.ring[i], block); break;
      case MapField::kScanIndex: AppendValue<uint32_t>(map.scan_index[i], block); break;
      case MapField::kDeviation:
        AppendValue<float>(static_cast<float>((*deviation_m)[i]), block);
        break;
    }
  }
}

// Point i of a chunk read back into the map's columns (ReadMapCloud).
void StoreMapField(MapField f, double v, MapCloud* map, std::vector<double>* deviation_m) {
  switch (f) {
    case MapField::kIntensity: map->intensity.push_back(static_cast<float>(v)); break;
    case MapField::kTime: map->t_ns.push_back(MapTimeNs(v)); break;
    case MapField::kRing: map->ring.push_back(static_cast<uint16_t>(v)); break;
    case MapField::kScanIndex: map->scan_index.push_back(static_cast<uint32_t>(v)); break;
    case MapField::kDeviation: deviation_m->push_back(v); break;
  }
}

// A map field whose value cannot be one of the map's (a negative ring, a
// fraction of a scan index, a non-finite time): InvalidInput naming the file.
Status CheckMapFieldValue(const std::string& path, const MapFieldSpec& f, double v, int64_t i) {
  bool ok = true;
  if (f.field == MapField::kTime) ok = std::isfinite(v) && std::abs(v) < 9.2e9;
  if (f.field == MapField::kRing) ok = v >= 0.0 && v <= 65535.0 && v == std::floor(v);
  if (f.field == MapField::kScanIndex) ok = v >= 0.0 && v <= 4294967295.0 && v == std::floor(v);
  if (ok) return Status::Ok();
  char text[64];
  std::snprintf(text, sizeof(text), "%.17g", v);
  return Status::InvalidInput(path + ": point " + std::to_string(i) + ": " + f.name + " " + text +
                              " is not a " + (f.field == MapField::kTime ? "time in seconds" : "whole number") +
                              " in its range");
}

}  // namespace

bool MapNeedsFloat64(const std::vector<Eigen::Vector3d>& p_world) {
  for (const Eigen::Vector3d& p : p_world)
    if (p.cwiseAbs().maxCoeff() >= kFloat32MillimetreReach_m) return true;
  return false;
}

void RoundToFloat32(std::vector<Eigen::Vector3d>* points) {
  if (points->empty()) return;
  // Over the coordinates as one flat array: GCC 12.2's SLP vectorizer (-O2
  // and up) drops the rounding of x and y in the per-point loop
  // `p = p.cast<float>().cast<double>()` (PointCloudFileTest.MapPointsAsStoredIsWhatTheFileGivesBack).
  static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "Vector3d is 3 packed doubles");
  double* xyz = points->front().data();
  for (size_t i = 0; i < 3 * points->size(); ++i)
    xyz[i] = static_cast<double>(static_cast<float>(xyz[i]));
}

std::vector<Eigen::Vector3d> MapPointsAsStored(std::vector<Eigen::Vector3d> p_world) {
  if (!MapNeedsFloat64(p_world)) RoundToFloat32(&p_world);
  return p_world;
}

Status WriteMapPcd(const std::string& path, const std::vector<Eigen::Vector3d>& p_world) {
  return WriteMapPcd(path, p_world, nullptr);
}

Status WriteMapPcd(const std::string& path, const std::vector<Eigen::Vector3d>& p_world,
                   const std::vector<double>* deviation_m) {
  MapCloud map;
  map.p = p_world;
  return WriteMapPcd(path, map, deviation_m);
}

Status WriteMapPcd(const std::string& path, const MapCloud& map,
                   const std::vector<double>* deviation_m) {
  // Not PCL's writer: it maps the file into memory after fallocate and throws
  // on failure, where a full disk must be a clean error that leaves no half
  // file. The points go through the atomic writer, byte for byte what
  // PCDWriter::writeBinary produces.
  RVLIO_CHECK(map.Consistent() && (deviation_m == nullptr || deviation_m->size() == map.size()));
  const int xyz_bytes = MapNeedsFloat64(map.p) ? 8 : 4;
  const std::vector<MapFieldSpec> attributes = MapAttributeFields(map, deviation_m != nullptr);
  size_t record_bytes = 3 * xyz_bytes;
  for (const MapFieldSpec& f : attributes) record_bytes += f.size;
  AtomicFileWriter writer;
  if (Status s = writer.Open(path); !s.ok()) return s;
  if (Status s = writer.Append(PcdBinaryHeader(map.size(), xyz_bytes, attributes)); !s.ok())
    return s;
  std::string block;
  block.reserve(kPcdBlockPoints * record_bytes);
  for (size_t i = 0; i < map.size(); ++i) {
    AppendPcdRecord(map, deviation_m, i, xyz_bytes, attributes, &block);
    if (block.size() >= kPcdBlockPoints * record_bytes || i + 1 == map.size()) {
      if (Status s = writer.Append(block); !s.ok()) return s;
      block.clear();
    }
  }
  return writer.Commit();
}

StatusOr<std::vector<Eigen::Vector3d>> ReadMapPcd(const std::string& path) {
  PointCloudReadOptions options;
  options.keep_fields = false;
  options.allow_empty = true;  // a run over too few scans writes an empty map
  StatusOr<PointCloudFile> cloud = ReadPointCloud(path, options);
  if (!cloud.ok()) return cloud.status();
  return std::move(cloud->points);
}

StatusOr<MapCloudFile> ReadMapCloud(const std::string& path) {
  PointCloudStream stream;
  if (Status s = stream.Open(path); !s.ok()) return s;
  std::vector<const MapFieldSpec*> roles;  // per stream field: its map field, or null
  MapCloudFile out;
  for (const PointCloudStreamField& f : stream.fields()) {
    const MapFieldSpec* spec = MapFieldByName(f.name);
    if (spec != nullptr && std::find(roles.begin(), roles.end(), spec) != roles.end())
      return Status::InvalidInput(path + ": field " + f.name + " appears twice");
    roles.push_back(spec);
    if (spec == nullptr) continue;
    out.map.has_intensity |= spec->field == MapField::kIntensity;
    out.map.has_time |= spec->field == MapField::kTime;
    out.map.has_ring |= spec->field == MapField::kRing;
    out.map.has_scan_index |= spec->field == MapField::kScanIndex;
    out.has_deviation |= spec->field == MapField::kDeviation;
    if (spec->field == MapField::kTime && !(f.type == 'F' && f.size == 8))
      return Status::InvalidInput(path + ": field time is " + f.type + std::to_string(f.size) +
                                  "; a map's time is absolute seconds in F8 (double)");
  }
  PointCloudChunk chunk;
  for (;;) {
    StatusOr<size_t> n = stream.Read(size_t{1} << 16, &chunk);
    if (!n.ok()) return n.status();
    if (*n == 0) break;
    for (size_t i = 0; i < *n; ++i) {
      const int64_t index = static_cast<int64_t>(out.map.size());
      out.map.p.push_back(chunk.points[i]);
      for (size_t k = 0; k < roles.size(); ++k) {
        if (roles[k] == nullptr) continue;
        const double v = chunk.fields[k][i];
        if (Status s = CheckMapFieldValue(path, *roles[k], v, index); !s.ok()) return s;
        StoreMapField(roles[k]->field, v, &out.map, &out.deviation_m);
      }
    }
  }
  return out;
}

std::string FormatSeconds(TimeNs t_ns) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.9f", NsToSeconds(t_ns));
  return buf;
}

Status WriteScansCsv(const std::string& path, const std::vector<ScanResult>& results,
                     const std::vector<double>& rss_mb) {
  const std::vector<const ScanColumn*> columns = ScanColumnsOf(results);
  std::string csv;
  for (const ScanColumn* c : columns)
    csv += (c == columns.front() ? "" : ",") + std::string(c->name);
  csv += '\n';
  for (size_t i = 0; i < results.size(); ++i) {
    const ScanRecord record{results[i], i < rss_mb.size() ? rss_mb[i] : std::nan("")};
    for (const ScanColumn* c : columns)
      csv += (c == columns.front() ? "" : ",") + FormatScanCell(*c, record);
    csv += '\n';
  }
  return WriteFileAtomically(path, csv);
}

Status WriteDeviationCsv(const std::string& path, const std::vector<DeviationBin>& bins) {
  std::ostringstream os;
  os.precision(6);
  os << "chainage_m,count,median_m,median_abs_m,p95_abs_m,max_abs_m";
  for (int k = 0; k < kTunnelSides; ++k) {  // per surface: left, right, floor, ceiling
    const std::string side = TunnelSideName(static_cast<TunnelSide>(k));
    os << ',' << side << "_count," << side << "_median_m," << side << "_p95_abs_m";
  }
  os << '\n';
  for (const DeviationBin& b : bins) {
    os << b.chainage_m << ',' << b.count << ',' << FormatFinite(b.median_m, 6) << ','
       << FormatFinite(b.median_abs_m, 6) << ',' << FormatFinite(b.p95_abs_m, 6) << ','
       << FormatFinite(b.max_abs_m, 6);
    for (const DeviationBin::Side& s : b.sides)
      os << ',' << s.count << ',' << FormatFinite(s.median_m, 6) << ','
         << FormatFinite(s.p95_abs_m, 6);
    os << '\n';
  }
  return WriteFileAtomically(path, os.str());
}

const std::vector<double>* ScanTable::Find(const std::string& name) const {
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return &columns[i];
  return nullptr;
}

StatusOr<ScanTable> ReadScanTable(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Status::InvalidInput(path + ": cannot open");
  std::string line;
  if (!std::getline(in, line) || line.rfind("t,", 0) != 0)
    return Status::InvalidInput(path + ": no CSV header with first column t");
  ScanTable table;
  std::istringstream header(line);
  for (std::string name; std::getline(header, name, ',');) table.names.push_back(name);
  table.columns.resize(table.names.size());
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::istringstream fields(line);
    std::string field;
    for (size_t i = 0; i < table.names.size(); ++i) {
      if (!std::getline(fields, field, ',')) field.clear();
      char* end = nullptr;
      double v = std::strtod(field.c_str(), &end);
      if (field.empty() || *end != '\0') v = std::nan("");
      if (table.names[i] == "diverged") v = field.empty() ? 0.0 : 1.0;
      table.columns[i].push_back(v);
    }
  }
  return table;
}

Trajectory ToTrajectory(const std::vector<ScanResult>& results) {
  Trajectory t;
  t.reserve(results.size());
  for (const ScanResult& r : results) {
    StampedPose p;
    p.t_ns = r.t_ns;
    p.p_world_imu = r.T_world_imu.t;
    p.q_world_imu = r.T_world_imu.quaternion();
    t.push_back(p);
  }
  return t;
}

Status WriteTrajectoryOutputs(OutputStage* stage, const Trajectory& trajectory,
                              const Trajectory& imu_trajectory) {
  if (Status s = WriteTum(stage->Path("trajectory.tum"), trajectory); !s.ok())
    return stage->Explain(s);
  if (imu_trajectory.empty()) return Status::Ok();
  if (Status s = WriteTum(stage->Path(kImuTrajectoryFile), imu_trajectory); !s.ok())
    return stage->Explain(s);
  return Status::Ok();
}

TimingStats ComputeTimingStats(const std::vector<ScanResult>& results) {
  TimingStats s;
  if (results.empty()) return s;
  std::vector<double> ms;
  ms.reserve(results.size());
  for (const auto& r : results) {
    ms.push_back(r.ms);
    s.total_ms += r.ms;
  }
  std::sort(ms.begin(), ms.end());
  const size_t n = ms.size();
  s.median_ms = Median(ms);
  s.p95_ms = ms[std::min(n - 1, static_cast<size_t>(0.95 * static_cast<double>(n)))];
  s.max_ms = ms.back();
  return s;
}

}  // namespace rvlio

#include "rvlio/outputs/run_outputs.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "rvlio/common/median.h"
#include "rvlio/common/text.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/math/local_origin.h"
#include "rvlio/outputs/scan_columns.h"

namespace rvlio {
namespace {

// The header of a binary PCD (v0.7) of n unorganized points with the fields
// x y z (float32, or float64 when xyz_bytes is 8), plus the float32
// `extra_field` when it is not empty: byte for byte the header PCL's
// PCDWriter::writeBinary writes for such a cloud (tests MapPcdIsWhatPclWritesAndReads,
// FarMapPcdIsFloat64AndWhatPclWrites), also for n = 0, which PCL refuses to write.
std::string PcdBinaryHeader(size_t n, int xyz_bytes, const std::string& extra_field) {
  const bool extra = !extra_field.empty();
  const std::string count = std::to_string(n);
  const std::string size = std::to_string(xyz_bytes);
  return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z" +
         (extra ? " " + extra_field : std::string()) + "\nSIZE " + size + " " + size + " " +
         size + (extra ? " 4" : "") + "\nTYPE F F F" + (extra ? " F" : "") + "\nCOUNT 1 1 1" +
         (extra ? " 1" : "") + "\nWIDTH " + count + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
         count + "\nDATA binary\n";
}

constexpr size_t kPcdBlockPoints = 1 << 15;  // points per Append of map.pcd

// One point's record: x y z as float32 or float64 (xyz_bytes), then the
// float32 deviation when deviation_m is not null.
void AppendPcdRecord(const Eigen::Vector3d& p, int xyz_bytes, const double* deviation_m,
                     std::string* block) {
  if (xyz_bytes == 8) {
    block->append(reinterpret_cast<const char*>(p.data()), 3 * sizeof(double));
  } else {
    const float xyz[3] = {static_cast<float>(p.x()), static_cast<float>(p.y()),
                          static_cast<float>(p.z())};
    block->append(reinterpret_cast<const char*>(xyz), sizeof(xyz));
  }
  if (deviation_m == nullptr) return;
  const float d = static_cast<float>(*deviation_m);
  block->append(reinterpret_cast<const char*>(&d), sizeof(d));
}

}  // namespace

bool MapNeedsFloat64(const std::vector<Eigen::Vector3d>& p_world) {
  for (const Eigen::Vector3d& p : p_world)
    if (p.cwiseAbs().maxCoeff() >= kFloat32MillimetreReach_m) return true;
  return false;
}

Status WriteMapPcd(const std::string& path, const std::vector<Eigen::Vector3d>& p_world) {
  return WriteMapPcd(path, p_world, nullptr);
}

Status WriteMapPcd(const std::string& path, const std::vector<Eigen::Vector3d>& p_world,
                   const std::vector<double>* deviation_m) {
  // Not PCL's writer: it maps the file into memory after fallocate and throws
  // on failure, where a full disk must be a clean error that leaves no half
  // file. The points go through the atomic writer, byte for byte what
  // PCDWriter::writeBinary produces.
  const int xyz_bytes = MapNeedsFloat64(p_world) ? 8 : 4;
  const std::string header =
      PcdBinaryHeader(p_world.size(), xyz_bytes, deviation_m != nullptr ? "deviation_m" : "");
  const size_t record_bytes = 3 * xyz_bytes + (deviation_m != nullptr ? sizeof(float) : 0);
  AtomicFileWriter writer;
  if (Status s = writer.Open(path); !s.ok()) return s;
  if (Status s = writer.Append(header); !s.ok()) return s;
  std::string block;
  block.reserve(kPcdBlockPoints * record_bytes);
  for (size_t i = 0; i < p_world.size(); ++i) {
    AppendPcdRecord(p_world[i], xyz_bytes, deviation_m != nullptr ? &(*deviation_m)[i] : nullptr,
                    &block);
    if (block.size() >= kPcdBlockPoints * record_bytes || i + 1 == p_world.size()) {
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

#include "rvlio/io/run_outputs.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "rvlio/io/atomic_file.h"
#include "rvlio/io/extrinsic_json.h"
#include "rvlio/io/point_cloud_file.h"

namespace rvlio {
namespace {

// The header of a binary PCD (v0.7) of n unorganized float32 points with the
// fields x y z, plus `extra_field` when it is not empty: byte for byte the
// header PCL's PCDWriter::writeBinary writes for such a cloud (test
// MapPcdIsWhatPclWritesAndReads), also for n = 0, which PCL refuses to write.
std::string PcdBinaryHeader(size_t n, const std::string& extra_field) {
  const bool extra = !extra_field.empty();
  const std::string count = std::to_string(n);
  return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z" +
         (extra ? " " + extra_field : std::string()) + "\nSIZE 4 4 4" + (extra ? " 4" : "") +
         "\nTYPE F F F" + (extra ? " F" : "") + "\nCOUNT 1 1 1" + (extra ? " 1" : "") +
         "\nWIDTH " + count + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + count +
         "\nDATA binary\n";
}

constexpr size_t kPcdBlockPoints = 1 << 15;  // points per Append of map.pcd

// The six extrinsic columns of a scan (empty if the scan carries no estimate).
void WriteExtrinsicColumns(const std::optional<Pose3>& T_imu_lidar, std::ostream& os) {
  if (!T_imu_lidar) {
    os << ",,,,,,";
    return;
  }
  const Eigen::Vector3d rpy = RpyDeg(T_imu_lidar->R);
  os << ',' << rpy.x() << ',' << rpy.y() << ',' << rpy.z() << ',' << T_imu_lidar->t.x() << ','
     << T_imu_lidar->t.y() << ',' << T_imu_lidar->t.z();
}

// The degeneracy columns: method, degenerate, count of weak translation
// directions, the weakest (world frame; empty without one), condition number.
void WriteDegeneracyColumns(const DegeneracyReport& d, std::ostream& os) {
  os << ',' << EnumName(d.method) << ',' << (d.degenerate ? 1 : 0) << ',' << d.num_weak;
  if (d.num_weak > 0) {
    const Eigen::Vector3d& w = d.weak_dirs_world[0];
    os << ',' << w.x() << ',' << w.y() << ',' << w.z();
  } else {
    os << ",,,";
  }
  os << ',';
  if (!std::isnan(d.condition_number)) os << d.condition_number;  // inf prints as inf
}

}  // namespace

Status WriteMapPcd(const std::string& path, const std::vector<Eigen::Vector3d>& p_world) {
  return WriteMapPcd(path, p_world, nullptr);
}

Status WriteMapPcd(const std::string& path, const std::vector<Eigen::Vector3d>& p_world,
                   const std::vector<double>* deviation_m) {
  // Not PCL's writer: it maps the file into memory after fallocate and throws
  // on failure, where a full disk must be a clean error that leaves no half
  // file. The points go through the atomic writer, byte for byte what
  // PCDWriter::writeBinary produces.
  const std::string header =
      PcdBinaryHeader(p_world.size(), deviation_m != nullptr ? "deviation_m" : "");
  const size_t fields = deviation_m != nullptr ? 4 : 3;
  AtomicFileWriter writer;
  if (Status s = writer.Open(path); !s.ok()) return s;
  if (Status s = writer.Append(header); !s.ok()) return s;
  std::string block;
  block.reserve(kPcdBlockPoints * fields * sizeof(float));
  for (size_t i = 0; i < p_world.size(); ++i) {
    const float row[4] = {static_cast<float>(p_world[i].x()), static_cast<float>(p_world[i].y()),
                          static_cast<float>(p_world[i].z()),
                          deviation_m != nullptr ? static_cast<float>((*deviation_m)[i]) : 0.0f};
    block.append(reinterpret_cast<const char*>(row), fields * sizeof(float));
    if (block.size() >= kPcdBlockPoints * fields * sizeof(float) || i + 1 == p_world.size()) {
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

namespace {
// A statistic that may be unknown (NaN): an empty field.
std::string Optional(double v) {
  if (!std::isfinite(v)) return "";
  std::ostringstream os;
  os.precision(6);
  os << v;
  return os.str();
}
}  // namespace

std::string FormatSeconds(TimeNs t_ns) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.9f", NsToSeconds(t_ns));
  return buf;
}

Status WriteScansCsv(const std::string& path, const std::vector<ScanResult>& results,
                     const std::vector<double>& rss_mb) {
  std::ostringstream os;
  os.precision(9);
  os << "t,status,raw_points,points,constraints,iterations,rv_active,n_alpha_x,n_alpha_y,"
        "n_alpha_z,scv,coplanar,repaired,K,rv_iterations,coplanar_fraction,localizability,"
        "ms,x,y,z,acc_x,acc_y,acc_z,rss_mb,reinforced,nis,residual_median_m,"
        "residual_rms_m,diverged,degeneracy_method,degenerate,weak_dirs,weak_dir_x,weak_dir_y,"
        "weak_dir_z,condition_number";
  // Online extrinsic estimation: its estimate after each scan (roll/pitch/yaw
  // in degrees as in summary.json, translation in metres).
  const bool extrinsic = std::any_of(results.begin(), results.end(),
                                     [](const ScanResult& r) { return r.T_imu_lidar.has_value(); });
  if (extrinsic) os << ",ext_roll_deg,ext_pitch_deg,ext_yaw_deg,ext_x_m,ext_y_m,ext_z_m";
  // Online time-offset estimation: its estimate and 1-sigma after each scan (s).
  const bool time_offset = std::any_of(results.begin(), results.end(), [](const ScanResult& r) {
    return r.time_offset_s.has_value();
  });
  if (time_offset) os << ",time_offset_s,time_offset_std_s";
  // Localization in a reference map (run --map).
  const bool reference = std::any_of(results.begin(), results.end(),
                                     [](const ScanResult& r) { return r.map_overlap.has_value(); });
  if (reference) os << ",map_overlap,localized";
  os << '\n';
  for (size_t i = 0; i < results.size(); ++i) {
    const ScanResult& r = results[i];
    const RvReport& v = r.rv;
    os << FormatSeconds(r.t_ns) << ',' << ScanStatusName(r.status) << ',' << r.raw_points << ','
       << r.downsampled_points << ',' << r.constraints << ',' << r.iterations << ','
       << (v.active ? 1 : 0) << ',' << v.n_alpha.x() << ',' << v.n_alpha.y() << ','
       << v.n_alpha.z() << ',' << v.num_scv << ',' << v.num_coplanar << ',' << v.num_repaired
       << ',' << v.K << ',' << v.iterations << ',' << v.coplanar_fraction << ','
       << v.localizability << ',' << r.ms << ',' << r.T_world_imu.t.x() << ','
       << r.T_world_imu.t.y() << ',' << r.T_world_imu.t.z() << ',' << r.mean_acc_imu.x() << ','
       << r.mean_acc_imu.y() << ',' << r.mean_acc_imu.z() << ','
       << (i < rss_mb.size() ? rss_mb[i] : std::nan("")) << ',' << v.num_reinforced << ','
       << Optional(r.health.nis_per_dof) << ',' << Optional(r.health.residual_median_m) << ','
       << Optional(r.health.residual_rms_m) << ',' << DivergenceKindNames(r.health.divergence_mask);
    WriteDegeneracyColumns(r.degeneracy, os);
    if (extrinsic) WriteExtrinsicColumns(r.T_imu_lidar, os);
    if (time_offset) {
      if (r.time_offset_s)
        os << ',' << *r.time_offset_s << ',' << r.time_offset_std_s;
      else
        os << ",,";
    }
    if (reference)
      os << ',' << (r.map_overlap ? Optional(*r.map_overlap) : "") << ',' << (r.localized ? 1 : 0);
    os << '\n';
  }
  return WriteFileAtomically(path, os.str());
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
    os << b.chainage_m << ',' << b.count << ',' << Optional(b.median_m) << ','
       << Optional(b.median_abs_m) << ',' << Optional(b.p95_abs_m) << ',' << Optional(b.max_abs_m);
    for (const DeviationBin::Side& s : b.sides)
      os << ',' << s.count << ',' << Optional(s.median_m) << ',' << Optional(s.p95_abs_m);
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
  s.median_ms = n % 2 ? ms[n / 2] : 0.5 * (ms[n / 2 - 1] + ms[n / 2]);
  s.p95_ms = ms[std::min(n - 1, static_cast<size_t>(0.95 * static_cast<double>(n)))];
  s.max_ms = ms.back();
  return s;
}

}  // namespace rvlio

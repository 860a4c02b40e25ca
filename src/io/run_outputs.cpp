#include "rvlio/io/run_outputs.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <sstream>

#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "rvlio/io/atomic_file.h"

namespace rvlio {
namespace {

// A valid PCD with no points (PCL refuses to write an empty cloud).
std::string EmptyPcd() {
  return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
         "TYPE F F F\nCOUNT 1 1 1\nWIDTH 0\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 0\n"
         "DATA binary\n";
}

// Absolute stamps need all nine decimals; the stream's precision is for the rest.
std::string FormatSeconds(TimeNs t_ns) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.9f", NsToSeconds(t_ns));
  return buf;
}

}  // namespace

Status WriteMapPcd(const std::string& path, const std::vector<Eigen::Vector3d>& p_world) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.reserve(p_world.size());
  for (const auto& p : p_world)
    cloud.push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                  static_cast<float>(p.z())));
  cloud.width = static_cast<uint32_t>(cloud.size());
  cloud.height = 1;
  cloud.is_dense = true;
  const std::string tmp = path + ".tmp";
  pcl::PCDWriter writer;
  if (cloud.empty() || writer.writeBinary(tmp, cloud) != 0) {
    std::remove(tmp.c_str());
    if (cloud.empty()) return WriteFileAtomically(path, EmptyPcd());
    return Status::InvalidInput("cannot write " + path);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp.c_str());
    return Status::InvalidInput("cannot write " + path + ": " + why);
  }
  return Status::Ok();
}

Status WriteScansCsv(const std::string& path, const std::vector<ScanResult>& results) {
  std::ostringstream os;
  os.precision(9);
  os << "t,status,raw_points,points,constraints,iterations,rv_active,n_alpha_x,n_alpha_y,"
        "n_alpha_z,scv,coplanar,repaired,K,rv_iterations,coplanar_fraction,localizability,"
        "ms,x,y,z,acc_x,acc_y,acc_z\n";
  for (const ScanResult& r : results) {
    const RvReport& v = r.rv;
    os << FormatSeconds(r.t_ns) << ',' << ScanStatusName(r.status) << ',' << r.raw_points << ','
       << r.downsampled_points << ',' << r.constraints << ',' << r.iterations << ','
       << (v.active ? 1 : 0) << ',' << v.n_alpha.x() << ',' << v.n_alpha.y() << ','
       << v.n_alpha.z() << ',' << v.num_scv << ',' << v.num_coplanar << ',' << v.num_repaired
       << ',' << v.K << ',' << v.iterations << ',' << v.coplanar_fraction << ','
       << v.localizability << ',' << r.ms << ',' << r.T_world_imu.t.x() << ','
       << r.T_world_imu.t.y() << ',' << r.T_world_imu.t.z() << ',' << r.mean_acc_imu.x() << ','
       << r.mean_acc_imu.y() << ',' << r.mean_acc_imu.z() << '\n';
  }
  return WriteFileAtomically(path, os.str());
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

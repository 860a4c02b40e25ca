#include "rvlio/outputs/scan_columns.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "rvlio/common/options.h"  // EnumName
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

constexpr double kNone = std::numeric_limits<double>::quiet_NaN();

using T = ScanValueType;
using F = ScanCsvFormat;
using G = ScanColumnGroup;
using R = const ScanRecord&;

double Ext(R r, int axis) {  // axis 0..2: roll pitch yaw (deg); 3..5: x y z (m)
  if (!r.scan.T_imu_lidar) return kNone;
  return axis < 3 ? RpyDeg(r.scan.T_imu_lidar->R)(axis) : r.scan.T_imu_lidar->t(axis - 3);
}

double WeakDir(R r, int axis) {  // the weakest direction (world frame); none without one
  const DegeneracyReport& d = r.scan.degeneracy;
  return d.num_weak > 0 ? d.weak_dirs_world[0](axis) : kNone;
}

// clang-format off
const std::vector<ScanColumn> kColumns = {
  {"t", "s", T::kReal, F::kSeconds, G::kAlways,  // scan end time
   [](R r) { return NsToSeconds(r.scan.t_ns); }, nullptr},
  {"status", "", T::kText, F::kPlain, G::kAlways,
   nullptr, [](R r) { return std::string(ScanStatusName(r.scan.status)); }},
  {"raw_points", "", T::kInteger, F::kPlain, G::kAlways,
   [](R r) { return double(r.scan.raw_points); }, nullptr},
  {"points", "", T::kInteger, F::kPlain, G::kAlways,  // after the downsampling
   [](R r) { return double(r.scan.downsampled_points); }, nullptr},
  {"constraints", "", T::kInteger, F::kPlain, G::kAlways,
   [](R r) { return double(r.scan.constraints); }, nullptr},
  {"iterations", "", T::kInteger, F::kPlain, G::kAlways,
   [](R r) { return double(r.scan.iterations); }, nullptr},
  {"rv_active", "", T::kFlag, F::kPlain, G::kAlways,
   [](R r) { return double(r.scan.rv.active); }, nullptr},
  {"n_alpha_x", "1", T::kReal, F::kPlain, G::kAlways,
   [](R r) { return r.scan.rv.n_alpha.x(); }, nullptr},
  {"n_alpha_y", "1", T::kReal, F::kPlain, G::kAlways,
   [](R r) { return r.scan.rv.n_alpha.y(); }, nullptr},
  {"n_alpha_z", "1", T::kReal, F::kPlain, G::kAlways,
   [](R r) { return r.scan.rv.n_alpha.z(); }, nullptr},
  {"scv", "", T::kInteger, F::kPlain, G::kAlways,
   [](R r) { return double(r.scan.rv.num_scv); }, nullptr},
  {"coplanar", "", T::kInteger, F::kPlain, G::kAlways,
   [](R r) { return double(r.scan.rv.num_coplanar); }, nullptr},
  {"repaired", "", T::kInteger, F::kPlain, G::kAlways,
   [](R r) { return double(r.scan.rv.num_repaired); }, nullptr},
  {"K", "1", T::kReal, F::kPlain, G::kAlways,
   [](R r) { return r.scan.rv.K; }, nullptr},
  {"rv_iterations", "", T::kInteger, F::kPlain, G::kAlways,
   [](R r) { return double(r.scan.rv.iterations); }, nullptr},
  {"coplanar_fraction", "1", T::kReal, F::kPlain, G::kAlways,
   [](R r) { return r.scan.rv.coplanar_fraction; }, nullptr},
  {"localizability", "1", T::kReal, F::kPlain, G::kAlways,  // sigma = 1
   [](R r) { return r.scan.rv.localizability; }, nullptr},
  {"ms", "ms", T::kReal, F::kPlain, G::kAlways,  // CPU time of the scan
   [](R r) { return r.scan.ms; }, nullptr},
  {"x", "m", T::kReal, F::kPosition, G::kAlways,  // IMU position in the world
   [](R r) { return r.scan.T_world_imu.t.x(); }, nullptr},
  {"y", "m", T::kReal, F::kPosition, G::kAlways,
   [](R r) { return r.scan.T_world_imu.t.y(); }, nullptr},
  {"z", "m", T::kReal, F::kPosition, G::kAlways,
   [](R r) { return r.scan.T_world_imu.t.z(); }, nullptr},
  {"acc_x", "m/s^2", T::kReal, F::kPlain, G::kAlways,  // mean specific force, IMU frame
   [](R r) { return r.scan.mean_acc_imu.x(); }, nullptr},
  {"acc_y", "m/s^2", T::kReal, F::kPlain, G::kAlways,
   [](R r) { return r.scan.mean_acc_imu.y(); }, nullptr},
  {"acc_z", "m/s^2", T::kReal, F::kPlain, G::kAlways,
   [](R r) { return r.scan.mean_acc_imu.z(); }, nullptr},
  {"rss_mb", "MB", T::kReal, F::kPlain, G::kAlways,  // resident memory when done
   [](R r) { return r.rss_mb; }, nullptr},
  {"reinforced", "", T::kInteger, F::kPlain, G::kAlways,
   [](R r) { return double(r.scan.rv.num_reinforced); }, nullptr},
  {"nis", "1", T::kReal, F::kStatistic, G::kAlways,  // per degree of freedom
   [](R r) { return r.scan.health.nis_per_dof; }, nullptr},
  {"residual_median_m", "m", T::kReal, F::kStatistic, G::kAlways,
   [](R r) { return r.scan.health.residual_median_m; }, nullptr},
  {"residual_rms_m", "m", T::kReal, F::kStatistic, G::kAlways,
   [](R r) { return r.scan.health.residual_rms_m; }, nullptr},
  {"diverged", "", T::kFlag, F::kPlain, G::kAlways,  // the CSV names the kinds that tripped
   [](R r) { return double(r.scan.health.divergence_mask != 0); },
   [](R r) { return DivergenceKindNames(r.scan.health.divergence_mask); }},
  {"degeneracy_method", "", T::kText, F::kPlain, G::kAlways,
   nullptr, [](R r) { return std::string(EnumName(r.scan.degeneracy.method)); }},
  {"degenerate", "", T::kFlag, F::kPlain, G::kAlways,
   [](R r) { return double(r.scan.degeneracy.degenerate); }, nullptr},
  {"weak_dirs", "", T::kInteger, F::kPlain, G::kAlways,
   [](R r) { return double(r.scan.degeneracy.num_weak); }, nullptr},
  {"weak_dir_x", "1", T::kReal, F::kRealOrEmpty, G::kAlways,
   [](R r) { return WeakDir(r, 0); }, nullptr},
  {"weak_dir_y", "1", T::kReal, F::kRealOrEmpty, G::kAlways,
   [](R r) { return WeakDir(r, 1); }, nullptr},
  {"weak_dir_z", "1", T::kReal, F::kRealOrEmpty, G::kAlways,
   [](R r) { return WeakDir(r, 2); }, nullptr},
  {"condition_number", "1", T::kReal, F::kRealOrEmpty, G::kAlways,
   [](R r) { return r.scan.degeneracy.condition_number; }, nullptr},
  {"vx", "m/s", T::kReal, F::kPlain, G::kAlways,  // IMU velocity in the world
   [](R r) { return r.scan.v_world_imu.x(); }, nullptr},
  {"vy", "m/s", T::kReal, F::kPlain, G::kAlways,
   [](R r) { return r.scan.v_world_imu.y(); }, nullptr},
  {"vz", "m/s", T::kReal, F::kPlain, G::kAlways,
   [](R r) { return r.scan.v_world_imu.z(); }, nullptr},
  {"ext_roll_deg", "deg", T::kReal, F::kRealOrEmpty, G::kExtrinsic,
   [](R r) { return Ext(r, 0); }, nullptr},
  {"ext_pitch_deg", "deg", T::kReal, F::kRealOrEmpty, G::kExtrinsic,
   [](R r) { return Ext(r, 1); }, nullptr},
  {"ext_yaw_deg", "deg", T::kReal, F::kRealOrEmpty, G::kExtrinsic,
   [](R r) { return Ext(r, 2); }, nullptr},
  {"ext_x_m", "m", T::kReal, F::kRealOrEmpty, G::kExtrinsic,
   [](R r) { return Ext(r, 3); }, nullptr},
  {"ext_y_m", "m", T::kReal, F::kRealOrEmpty, G::kExtrinsic,
   [](R r) { return Ext(r, 4); }, nullptr},
  {"ext_z_m", "m", T::kReal, F::kRealOrEmpty, G::kExtrinsic,
   [](R r) { return Ext(r, 5); }, nullptr},
  {"time_offset_s", "s", T::kReal, F::kRealOrEmpty, G::kTimeOffset,
   [](R r) { return r.scan.time_offset_s ? *r.scan.time_offset_s : kNone; }, nullptr},
  {"time_offset_std_s", "s", T::kReal, F::kRealOrEmpty, G::kTimeOffset,
   [](R r) { return r.scan.time_offset_s ? r.scan.time_offset_std_s : kNone; }, nullptr},
  {"map_overlap", "1", T::kReal, F::kStatistic, G::kReference,
   [](R r) { return r.scan.map_overlap ? *r.scan.map_overlap : kNone; }, nullptr},
  {"localized", "", T::kFlag, F::kPlain, G::kReference,
   [](R r) { return double(r.scan.localized); }, nullptr},
};
// clang-format on

bool Carries(const ScanResult& r, ScanColumnGroup group) {
  switch (group) {
    case G::kAlways:
      return true;
    case G::kExtrinsic:
      return r.T_imu_lidar.has_value();
    case G::kTimeOffset:
      return r.time_offset_s.has_value();
    case G::kReference:
      return r.map_overlap.has_value();
  }
  return false;
}

}  // namespace

const std::vector<ScanColumn>& AllScanColumns() { return kColumns; }

std::vector<const ScanColumn*> ScanColumnsOf(const std::vector<ScanResult>& scans) {
  std::vector<const ScanColumn*> columns;
  for (const ScanColumn& c : kColumns) {
    if (c.group == G::kAlways || std::any_of(scans.begin(), scans.end(), [&](const ScanResult& r) {
          return Carries(r, c.group);
        }))
      columns.push_back(&c);
  }
  return columns;
}

std::string FormatScanCell(const ScanColumn& column, const ScanRecord& record) {
  if (column.text) return column.text(record);
  const double v = column.value(record);
  if (column.type == T::kFlag) return v != 0.0 ? "1" : "0";
  if (column.type == T::kInteger) return std::to_string(static_cast<long long>(v));
  if (column.format == F::kSeconds) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.9f", v);
    return buf;
  }
  if (column.format == F::kRealOrEmpty && std::isnan(v)) return "";
  if (column.format == F::kStatistic && !std::isfinite(v)) return "";
  std::ostringstream os;
  os.precision(column.format == F::kStatistic ? 6 : 9);
  if (column.format == F::kPosition && std::isfinite(v) && std::abs(v) >= 1.0)  // >= 6 decimals
    os.precision(std::max(9, static_cast<int>(std::floor(std::log10(std::abs(v)))) + 7));
  os << v;
  return os.str();
}

}  // namespace rvlio

#include "sensor_writer_common.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace rvlio::bag_detail {
namespace {

// The Ouster driver's point (ouster_ros): x y z at 0/4/8, padding, intensity
// at 16, t at 20, reflectivity 24, ring 26, ambient 28, range 32; 48 bytes.
struct OusterField {
  const char* name;
  uint32_t offset;
  uint8_t datatype;
};
constexpr OusterField kOusterFields[] = {
    {"x", 0, kPointFloat32},
    {"y", 4, kPointFloat32},
    {"z", 8, kPointFloat32},
    {"intensity", 16, kPointFloat32},
    {"t", 20, kPointUint32},
    {"reflectivity", 24, kPointUint16},
    {"ring", 26, kPointUint16},
    {"ambient", 28, kPointUint16},
    {"range", 32, kPointUint32},
};
constexpr uint32_t kOusterPointStep = 48;

template <typename T>
void Put(uint8_t* dst, uint32_t offset, T value) {
  std::memcpy(dst + offset, &value, sizeof(T));
}

bool IsNoReturn(const LidarPoint& p) { return p.p_lidar.isZero(0.0f); }

uint16_t ClampU16(double v) {
  if (!(v > 0.0)) return 0;
  return v >= 65535.0 ? uint16_t{65535} : static_cast<uint16_t>(std::lround(v));
}

}  // namespace

Status BuildOusterCloud(const Scan& scan, int rows, int cols, OwnedCloud* out) {
  const size_t n = scan.points.size();
  const bool organized = rows > 0 && cols > 0 && static_cast<size_t>(rows) * cols == n;
  PointCloud2View& v = out->view;
  v.header_stamp_ns = scan.t_start_ns;
  v.height = organized ? rows : 1;
  v.width = organized ? cols : static_cast<uint32_t>(n);
  v.is_bigendian = false;
  out->is_dense = !organized;
  v.point_step = kOusterPointStep;
  v.row_step = kOusterPointStep * v.width;
  v.fields.clear();
  for (const auto& f : kOusterFields) v.fields.push_back({f.name, f.offset, f.datatype, 1});
  out->data.assign(n * kOusterPointStep, 0);
  for (size_t i = 0; i < n; ++i) {
    const LidarPoint& p = scan.points[i];
    uint32_t t = 0;
    if (Status s = RelativePointTime(scan, p, i, &t); !s.ok()) return s;
    uint8_t* dst = out->data.data() + i * kOusterPointStep;
    Put<float>(dst, 0, p.p_lidar.x());
    Put<float>(dst, 4, p.p_lidar.y());
    Put<float>(dst, 8, p.p_lidar.z());
    Put<float>(dst, 16, p.intensity);
    Put<uint32_t>(dst, 20, t);
    Put<uint16_t>(dst, 24, ClampU16(p.intensity));
    Put<uint16_t>(dst, 26, p.ring);
    Put<uint16_t>(dst, 28, 0);
    const double range_mm = 1000.0 * p.p_lidar.cast<double>().norm();
    Put<uint32_t>(dst, 32, std::isfinite(range_mm) && range_mm < 4.0e9
                               ? static_cast<uint32_t>(std::lround(range_mm)) : 0u);
  }
  v.data = out->data.data();
  v.data_size = out->data.size();
  return Status::Ok();
}

Status RelativePointTime(const Scan& scan, const LidarPoint& p, size_t index, uint32_t* t) {
  const TimeNs dt = p.t_ns - scan.t_start_ns;
  if (dt >= 0 && dt <= static_cast<TimeNs>(std::numeric_limits<uint32_t>::max())) {
    *t = static_cast<uint32_t>(dt);
    return Status::Ok();
  }
  if (IsNoReturn(p)) {
    *t = 0;
    return Status::Ok();
  }
  return Status::InvalidInput("point " + std::to_string(index) + " time " +
                              std::to_string(p.t_ns) + " ns is not within 4.29 s after the scan "
                              "start " + std::to_string(scan.t_start_ns) + " ns");
}

Status CheckRelativePointTimes(const Scan& scan) {
  for (size_t i = 0; i < scan.points.size(); ++i) {
    uint32_t t = 0;
    if (Status s = RelativePointTime(scan, scan.points[i], i, &t); !s.ok()) return s;
  }
  return Status::Ok();
}

Status CheckStamp(TimeNs t_ns, TimeNs max_ns, const std::string& range_text,
                  const std::string& what) {
  if (t_ns < 0 || t_ns > max_ns) {
    return Status::InvalidInput(what + " " + std::to_string(t_ns) + " ns is outside the " +
                                range_text);
  }
  return Status::Ok();
}

}  // namespace rvlio::bag_detail

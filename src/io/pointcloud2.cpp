#include "rvlio/io/pointcloud2.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

namespace rvlio {
namespace {

// Relative point times beyond this are corrupt, not a slow scanner.
constexpr double kMaxRelativeNs = 3600.0 * 1e9;
// Absolute times must fit int64 nanoseconds with room for arithmetic.
constexpr double kMaxAbsoluteNs = 4.0e18;

enum class TimeKind { kRelativeNs, kRelativeS, kAbsoluteS, kAbsoluteNsOrS };

struct FieldRef {
  bool present = false;
  uint32_t offset = 0;
  uint8_t datatype = 0;
};

struct Layout {
  std::string name;
  FieldRef time;
  TimeKind kind = TimeKind::kRelativeNs;
};

bool HostIsBigEndian() {
  const uint16_t one = 1;
  uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 0;
}

template <typename T>
double Load(const uint8_t* p, bool swap) {
  uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, p, sizeof(T));
  if (swap) std::reverse(bytes, bytes + sizeof(T));
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return static_cast<double>(value);
}

// Reads one element; the caller has checked that it lies inside the data.
double ReadScalar(const uint8_t* p, uint8_t datatype, bool swap) {
  switch (datatype) {
    case kPointInt8: return Load<int8_t>(p, swap);
    case kPointUint8: return Load<uint8_t>(p, swap);
    case kPointInt16: return Load<int16_t>(p, swap);
    case kPointUint16: return Load<uint16_t>(p, swap);
    case kPointInt32: return Load<int32_t>(p, swap);
    case kPointUint32: return Load<uint32_t>(p, swap);
    case kPointFloat32: return Load<float>(p, swap);
    case kPointFloat64: return Load<double>(p, swap);
    default: return std::numeric_limits<double>::quiet_NaN();
  }
}

std::string Where(const PointCloud2View& cloud) {
  return "PointCloud2" + (cloud.topic.empty() ? std::string() : " on " + cloud.topic);
}

FieldRef Find(const PointCloud2View& cloud, const char* name) {
  FieldRef ref;
  for (const auto& f : cloud.fields) {
    if (f.name == name) {
      ref.present = true;
      ref.offset = f.offset;
      ref.datatype = f.datatype;
      return ref;
    }
  }
  return ref;
}

// Every field inside point_step, rows inside row_step, rows inside the data.
Status ValidateGeometry(const PointCloud2View& cloud) {
  std::ostringstream err;
  err << Where(cloud) << ": ";
  for (const auto& f : cloud.fields) {
    const uint64_t size = PointFieldSize(f.datatype);
    if (size == 0) {
      err << "field '" << f.name << "' has unknown datatype " << int(f.datatype);
      return Status::InvalidInput(err.str());
    }
    const uint64_t end = uint64_t{f.offset} + size * std::max<uint64_t>(f.count, 1);
    if (end > cloud.point_step) {
      err << "field '" << f.name << "' (offset " << f.offset << ", " << end - f.offset
          << " bytes) does not fit in point_step " << cloud.point_step;
      return Status::InvalidInput(err.str());
    }
  }
  const uint64_t points = uint64_t{cloud.height} * cloud.width;
  if (points > 0 && cloud.point_step == 0) {
    err << "point_step is 0 for " << points << " points";
    return Status::InvalidInput(err.str());
  }
  const uint64_t row_bytes = uint64_t{cloud.point_step} * cloud.width;
  if (cloud.height > 0 && cloud.row_step < row_bytes) {
    err << "row_step " << cloud.row_step << " is smaller than point_step * width = " << row_bytes;
    return Status::InvalidInput(err.str());
  }
  const uint64_t needed = uint64_t{cloud.row_step} * cloud.height;
  if (points > 0 && cloud.data_size < needed) {
    err << "data has " << cloud.data_size << " bytes, row_step * height needs " << needed;
    return Status::InvalidInput(err.str());
  }
  if (cloud.data_size > 0 && cloud.data == nullptr) {
    err << "data pointer is null";
    return Status::InvalidInput(err.str());
  }
  return Status::Ok();
}

Status NoTimeField(const PointCloud2View& cloud, const std::string& type,
                   const std::string& wanted) {
  std::string msg = Where(cloud);
  if (type == "auto") {
    msg += " has no per-point time field; fields are " + PointFieldNames(cloud.fields) +
           "; set lidar.type or use a driver that stamps points";
  } else {
    msg += " has no field " + wanted + " required by lidar.type=" + type + "; fields are " +
           PointFieldNames(cloud.fields);
  }
  return Status::InvalidInput(msg);
}

StatusOr<Layout> SelectLayout(const PointCloud2View& cloud, const std::string& type) {
  const FieldRef t = Find(cloud, "t"), time = Find(cloud, "time");
  const FieldRef stamp = Find(cloud, "timestamp"), offset = Find(cloud, "offset_time");
  const bool livox_fields = Find(cloud, "line").present || Find(cloud, "tag").present;
  std::string name = type;
  if (type == "auto") {
    if (t.present) name = "ouster";
    else if (time.present) name = "velodyne";
    else if (stamp.present) name = livox_fields ? "livox" : "hesai";
    else if (offset.present) name = "livox";
    else return NoTimeField(cloud, type, "");
  }
  Layout layout;
  layout.name = name;
  if (name == "ouster") {
    layout.time = t;
    layout.kind = TimeKind::kRelativeNs;
    if (!t.present) return NoTimeField(cloud, type, "'t'");
  } else if (name == "velodyne") {
    layout.time = time;
    layout.kind = TimeKind::kRelativeS;
    if (!time.present) return NoTimeField(cloud, type, "'time'");
  } else if (name == "hesai") {
    layout.time = stamp;
    layout.kind = TimeKind::kAbsoluteS;
    if (!stamp.present) return NoTimeField(cloud, type, "'timestamp'");
  } else if (name == "livox") {
    layout.time = stamp.present ? stamp : offset;
    layout.kind = stamp.present ? TimeKind::kAbsoluteNsOrS : TimeKind::kRelativeNs;
    if (!layout.time.present) return NoTimeField(cloud, type, "'timestamp' or 'offset_time'");
  } else {
    return Status::InvalidInput("lidar.type '" + type +
                                "' is not one of auto, ouster, velodyne, hesai, livox");
  }
  return layout;
}

// Iterates the points row by row; the geometry has been validated.
class PointCursor {
 public:
  explicit PointCursor(const PointCloud2View& cloud)
      : cloud_(cloud), swap_(cloud.is_bigendian != HostIsBigEndian()) {}
  uint64_t size() const { return uint64_t{cloud_.height} * cloud_.width; }
  const uint8_t* Point(uint64_t i) const {
    const uint64_t row = i / cloud_.width, col = i % cloud_.width;
    return cloud_.data + row * cloud_.row_step + col * cloud_.point_step;
  }
  double Read(uint64_t i, const FieldRef& f) const {
    return ReadScalar(Point(i) + f.offset, f.datatype, swap_);
  }

 private:
  const PointCloud2View& cloud_;
  bool swap_;
};

// Time field of point i in its native scale: ns for relative layouts, the
// raw value for absolute ones. NaN when unusable.
double RawTime(const PointCursor& cursor, uint64_t i, const Layout& layout) {
  double v = cursor.Read(i, layout.time);
  if (!std::isfinite(v)) return std::numeric_limits<double>::quiet_NaN();
  if (layout.kind == TimeKind::kRelativeS) v *= 1e9;
  const bool relative =
      layout.kind == TimeKind::kRelativeNs || layout.kind == TimeKind::kRelativeS;
  if (relative && std::abs(v) > kMaxRelativeNs) return std::numeric_limits<double>::quiet_NaN();
  return v;
}

struct TimeRange {
  int64_t valid = 0, negative = 0;
  double min = 0.0, max = 0.0;
};

TimeRange ScanTimes(const PointCursor& cursor, const Layout& layout) {
  TimeRange r;
  for (uint64_t i = 0; i < cursor.size(); ++i) {
    const double v = RawTime(cursor, i, layout);
    if (std::isnan(v)) continue;
    r.min = r.valid == 0 ? v : std::min(r.min, v);
    r.max = r.valid == 0 ? v : std::max(r.max, v);
    r.negative += v < 0.0;
    ++r.valid;
  }
  return r;
}

// Maps a raw time value to absolute ns: relative layouts add the raw value
// (ns) plus a shift to the integer stamp, so that no precision is lost.
struct TimeMapping {
  bool relative = true;
  TimeNs stamp_ns = 0;
  double shift_ns = 0.0;
  bool seconds = true;  // absolute: raw value in s (else ns)
};

TimeMapping RelativeMapping(const PointCloud2View& cloud, const TimeRange& range,
                            const std::string& header_stamp, DecodeStats* stats) {
  const bool mostly_negative = 2 * range.negative > range.valid;
  double shift = 0.0;
  if (header_stamp == "start") {
    stats->stamp_is_end = false;
    if (mostly_negative) shift = -range.min;
  } else if (header_stamp == "end") {
    stats->stamp_is_end = true;
    if (!mostly_negative) shift = -range.max;
  } else {
    stats->stamp_is_end = mostly_negative;
  }
  TimeMapping m;
  m.stamp_ns = cloud.header_stamp_ns;
  m.shift_ns = shift;
  return m;
}

// Absolute layouts: seconds, or (livox) ns or s, whichever lands nearer the
// header stamp. The stamp marks the end when it is nearer the latest time.
TimeMapping AbsoluteMapping(const PointCloud2View& cloud, const Layout& layout,
                            const TimeRange& range, DecodeStats* stats) {
  TimeMapping m;
  m.relative = false;
  const double stamp = static_cast<double>(cloud.header_stamp_ns);
  if (layout.kind == TimeKind::kAbsoluteNsOrS && range.valid > 0 &&
      std::abs(range.max - stamp) < std::abs(range.max * 1e9 - stamp)) {
    m.seconds = false;
  }
  if (range.valid > 0) {
    const double scale = m.seconds ? 1e9 : 1.0;
    stats->stamp_is_end =
        std::abs(stamp - range.max * scale) < std::abs(stamp - range.min * scale);
  }
  return m;
}

// Absolute ns of a raw time, or false when it is unusable. Absolute seconds
// are split into whole and fractional seconds to keep the double's precision.
bool ToAbsoluteNs(double raw, const TimeMapping& m, TimeNs* t_ns) {
  if (std::isnan(raw)) return false;
  if (m.relative) {
    *t_ns = m.stamp_ns + static_cast<TimeNs>(std::llround(raw + m.shift_ns));
    return true;
  }
  const double ns = m.seconds ? raw * 1e9 : raw;
  if (!(std::abs(ns) < kMaxAbsoluteNs)) return false;
  if (!m.seconds) {
    *t_ns = static_cast<TimeNs>(std::llround(raw));
    return true;
  }
  const double whole_s = std::floor(raw);
  *t_ns = static_cast<TimeNs>(whole_s) * kNsPerSecond +
          static_cast<TimeNs>(std::llround((raw - whole_s) * 1e9));
  return true;
}

struct PointFields {
  FieldRef x, y, z, intensity, ring;
};

Status FindPointFields(const PointCloud2View& cloud, const Layout& layout, PointFields* f) {
  f->x = Find(cloud, "x");
  f->y = Find(cloud, "y");
  f->z = Find(cloud, "z");
  if (!f->x.present || !f->y.present || !f->z.present) {
    return Status::InvalidInput(Where(cloud) + " has no x, y, z fields; fields are " +
                                PointFieldNames(cloud.fields));
  }
  f->intensity = Find(cloud, "intensity");
  f->ring = Find(cloud, "ring");
  if (!f->ring.present && layout.name == "livox") f->ring = Find(cloud, "line");
  return Status::Ok();
}

uint16_t ToRing(double v) {
  if (!(v >= 0.0 && v <= 65535.0)) return 0;
  return static_cast<uint16_t>(v);
}

void DecodePoints(const PointCursor& cursor, const Layout& layout, const PointFields& f,
                  const TimeMapping& mapping, const LidarOptions& lidar, Scan* scan,
                  DecodeStats* stats) {
  scan->points.reserve(cursor.size());
  for (uint64_t i = 0; i < cursor.size(); ++i) {
    LidarPoint p;
    const bool time_ok = ToAbsoluteNs(RawTime(cursor, i, layout), mapping, &p.t_ns);
    if (!FilterPoint(cursor.Read(i, f.x), cursor.Read(i, f.y), cursor.Read(i, f.z), time_ok,
                     lidar, stats, &p.p_lidar))
      continue;
    if (f.intensity.present) {
      const double v = cursor.Read(i, f.intensity);
      p.intensity = std::isfinite(v) && std::abs(v) < 1e30 ? float(v) : 0.0f;
    }
    if (f.ring.present) p.ring = ToRing(cursor.Read(i, f.ring));
    scan->points.push_back(p);
  }
}

}  // namespace

bool FilterPoint(double x, double y, double z, bool time_ok, const LidarOptions& lidar,
                 DecodeStats* stats, Eigen::Vector3f* p_lidar) {
  const bool finite = std::isfinite(x) && std::isfinite(y) && std::isfinite(z) &&
                      std::abs(x) < 1e9 && std::abs(y) < 1e9 && std::abs(z) < 1e9;
  // The zero and range tests use the stored float coordinates: a float64
  // coordinate of 1e-50 becomes 0 and must not slip through as a point.
  if (finite) *p_lidar = Eigen::Vector3f(float(x), float(y), float(z));
  if (!finite || p_lidar->isZero(0.0f) || !time_ok) {
    ++stats->invalid_points;
    return false;
  }
  const double r2 = p_lidar->cast<double>().squaredNorm();
  if (r2 < lidar.min_range * lidar.min_range || r2 > lidar.max_range * lidar.max_range) {
    ++stats->out_of_range_points;
    return false;
  }
  return true;
}

void SetScanTimeBounds(TimeNs fallback_ns, Scan* scan) {
  scan->t_start_ns = scan->t_end_ns = fallback_ns;
  if (scan->points.empty()) return;
  const auto [lo, hi] = std::minmax_element(
      scan->points.begin(), scan->points.end(),
      [](const LidarPoint& a, const LidarPoint& b) { return a.t_ns < b.t_ns; });
  scan->t_start_ns = lo->t_ns;
  scan->t_end_ns = hi->t_ns;
}

size_t PointFieldSize(uint8_t datatype) {
  switch (datatype) {
    case kPointInt8: case kPointUint8: return 1;
    case kPointInt16: case kPointUint16: return 2;
    case kPointInt32: case kPointUint32: case kPointFloat32: return 4;
    case kPointFloat64: return 8;
    default: return 0;
  }
}

std::string PointFieldNames(const std::vector<PointField>& fields) {
  std::string names;
  for (const auto& f : fields) names += (names.empty() ? "" : ",") + f.name;
  return names.empty() ? "(none)" : names;
}

StatusOr<std::string> DetectPointCloud2Layout(const PointCloud2View& cloud,
                                              const std::string& type) {
  StatusOr<Layout> layout = SelectLayout(cloud, type);
  if (!layout.ok()) return layout.status();
  return layout->name;
}

StatusOr<Scan> DecodePointCloud2(const PointCloud2View& cloud, const LidarOptions& lidar,
                                 DecodeStats* stats_out) {
  DecodeStats local;
  DecodeStats* stats = stats_out ? stats_out : &local;
  *stats = DecodeStats();
  if (Status s = ValidateGeometry(cloud); !s.ok()) return s;
  if (std::abs(static_cast<double>(cloud.header_stamp_ns)) > kMaxAbsoluteNs / 2) {
    return Status::InvalidInput(Where(cloud) + ": header stamp out of range");
  }
  StatusOr<Layout> layout = SelectLayout(cloud, lidar.type);
  if (!layout.ok()) return layout.status();
  PointFields fields;
  if (Status s = FindPointFields(cloud, *layout, &fields); !s.ok()) return s;

  const PointCursor cursor(cloud);
  stats->layout = layout->name;
  stats->raw_points = static_cast<int64_t>(cursor.size());
  const TimeRange range = ScanTimes(cursor, *layout);
  const bool relative =
      layout->kind == TimeKind::kRelativeNs || layout->kind == TimeKind::kRelativeS;
  const TimeMapping mapping = relative
                                  ? RelativeMapping(cloud, range, lidar.header_stamp, stats)
                                  : AbsoluteMapping(cloud, *layout, range, stats);
  Scan scan;
  DecodePoints(cursor, *layout, fields, mapping, lidar, &scan, stats);
  SetScanTimeBounds(cloud.header_stamp_ns, &scan);
  return scan;
}

}  // namespace rvlio

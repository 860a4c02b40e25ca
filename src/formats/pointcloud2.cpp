#include "rvlio/formats/pointcloud2.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <type_traits>

#include "rvlio/lidar/range_window.h"

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

// Calls fn(point) for every point, row by row; the geometry has been validated.
template <typename Fn>
void ForEachPoint(const PointCloud2View& cloud, Fn&& fn) {
  if (cloud.width == 0) return;  // no points, however many (empty) rows
  for (uint32_t row = 0; row < cloud.height; ++row) {
    const uint8_t* point = cloud.data + uint64_t{row} * cloud.row_step;
    for (uint32_t col = 0; col < cloud.width; ++col, point += cloud.point_step) fn(point);
  }
}

// Time field value in its native scale: ns for relative layouts, the raw
// value for absolute ones. NaN when unusable.
double NormalizeTime(double v, TimeKind kind) {
  if (!std::isfinite(v)) return std::numeric_limits<double>::quiet_NaN();
  if (kind == TimeKind::kRelativeS) v *= 1e9;
  const bool relative = kind == TimeKind::kRelativeNs || kind == TimeKind::kRelativeS;
  if (relative && std::abs(v) > kMaxRelativeNs) return std::numeric_limits<double>::quiet_NaN();
  return v;
}

struct PointFields {
  FieldRef x, y, z, intensity, ring;
};

// Reads the fields of a point of any layout: each element through its
// datatype code, byte-swapped when the cloud's byte order is not the host's.
class GenericReader {
 public:
  GenericReader(const PointCloud2View& cloud, const Layout& layout, const PointFields& f)
      : layout_(layout), f_(f), swap_(cloud.is_bigendian != HostIsBigEndian()) {}
  double Time(const uint8_t* p) const { return NormalizeTime(Read(p, layout_.time), layout_.kind); }
  double X(const uint8_t* p) const { return Read(p, f_.x); }
  double Y(const uint8_t* p) const { return Read(p, f_.y); }
  double Z(const uint8_t* p) const { return Read(p, f_.z); }
  bool has_intensity() const { return f_.intensity.present; }
  double Intensity(const uint8_t* p) const { return Read(p, f_.intensity); }
  bool has_ring() const { return f_.ring.present; }
  double Ring(const uint8_t* p) const { return Read(p, f_.ring); }

 private:
  double Read(const uint8_t* p, const FieldRef& f) const {
    return ReadScalar(p + f.offset, f.datatype, swap_);
  }
  const Layout& layout_;
  const PointFields& f_;
  bool swap_;
};

// No field of this kind (fast path template argument).
struct Absent {};

template <typename T>
double LoadHost(const uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return static_cast<double>(value);
}

// The common relative-time layouts (Ouster, Velodyne, Livox offset_time) in
// host byte order: x, y, z float32, time TimeT (uint32 ns or float32 s),
// intensity float32, uint16 or uint8 (Ouster's reflectivity) or absent, ring
// RingT (uint8, uint16 or Absent). Every value is the double GenericReader
// reads, so both decode the same points.
template <typename TimeT, bool kIntensity, typename RingT>
class FastReader {
 public:
  FastReader(const Layout& layout, const PointFields& f)
      : kind_(layout.kind), t_(layout.time.offset), x_(f.x.offset), y_(f.y.offset),
        z_(f.z.offset), i_(f.intensity.offset), r_(f.ring.offset),
        i_type_(f.intensity.datatype) {}
  double Time(const uint8_t* p) const { return NormalizeTime(LoadHost<TimeT>(p + t_), kind_); }
  double X(const uint8_t* p) const { return LoadHost<float>(p + x_); }
  double Y(const uint8_t* p) const { return LoadHost<float>(p + y_); }
  double Z(const uint8_t* p) const { return LoadHost<float>(p + z_); }
  static constexpr bool has_intensity() { return kIntensity; }
  double Intensity(const uint8_t* p) const {  // the same type in every point: predicted
    if (i_type_ == kPointFloat32) return LoadHost<float>(p + i_);
    if (i_type_ == kPointUint16) return LoadHost<uint16_t>(p + i_);
    return LoadHost<uint8_t>(p + i_);
  }
  static constexpr bool has_ring() { return !std::is_same<RingT, Absent>::value; }
  double Ring(const uint8_t* p) const {
    if constexpr (has_ring()) return LoadHost<RingT>(p + r_);
    return 0.0;
  }

 private:
  TimeKind kind_;
  uint32_t t_, x_, y_, z_, i_, r_;
  uint8_t i_type_;
};

struct TimeRange {
  int64_t valid = 0, negative = 0;
  double min = 0.0, max = 0.0;
};

template <typename Reader>
TimeRange ScanTimes(const PointCloud2View& cloud, const Reader& reader) {
  TimeRange r;
  ForEachPoint(cloud, [&](const uint8_t* point) {
    const double v = reader.Time(point);
    if (std::isnan(v)) return;
    r.min = r.valid == 0 ? v : std::min(r.min, v);
    r.max = r.valid == 0 ? v : std::max(r.max, v);
    r.negative += v < 0.0;
    ++r.valid;
  });
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

// std::llround(v) without a libm call for |v| < 2^52, where the truncation
// and the fraction v - trunc(v) are exact (relative times are < 3.6e12 ns).
int64_t RoundHalfAwayFromZero(double v) {
  if (!(std::abs(v) < 4.5e15)) return std::llround(v);
  const int64_t i = static_cast<int64_t>(v);
  const double frac = v - static_cast<double>(i);
  return i + (frac >= 0.5 ? 1 : 0) - (frac <= -0.5 ? 1 : 0);
}

// Absolute ns of a raw time, or false when it is unusable. Absolute seconds
// are split into whole and fractional seconds to keep the double's precision.
bool ToAbsoluteNs(double raw, const TimeMapping& m, TimeNs* t_ns) {
  if (std::isnan(raw)) return false;
  if (m.relative) {
    *t_ns = m.stamp_ns + static_cast<TimeNs>(RoundHalfAwayFromZero(raw + m.shift_ns));
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

Status FindPointFields(const PointCloud2View& cloud, const Layout& layout, PointFields* f) {
  f->x = Find(cloud, "x");
  f->y = Find(cloud, "y");
  f->z = Find(cloud, "z");
  if (!f->x.present || !f->y.present || !f->z.present) {
    return Status::InvalidInput(Where(cloud) + " has no x, y, z fields; fields are " +
                                PointFieldNames(cloud.fields));
  }
  // The sensor's reflectivity where the layout gives one (Ouster), else its
  // intensity (docs/input_formats.md).
  f->intensity = Find(cloud, "reflectivity");
  if (!f->intensity.present) f->intensity = Find(cloud, "intensity");
  f->ring = Find(cloud, "ring");
  if (!f->ring.present && layout.name == "livox") f->ring = Find(cloud, "line");
  return Status::Ok();
}

uint16_t ToRing(double v) {
  if (!(v >= 0.0 && v <= 65535.0)) return 0;
  return static_cast<uint16_t>(v);
}

// FilterPoint (pointcloud2.h), inlined into the decoding loops.
inline bool KeepPoint(double x, double y, double z, bool time_ok, const LidarOptions& lidar,
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
  if (!RangeWindow(lidar).Contains(r2)) {
    ++stats->out_of_range_points;
    return false;
  }
  return true;
}

template <typename Reader>
void DecodePoints(const PointCloud2View& cloud, const Reader& reader, const TimeMapping& mapping,
                  const LidarOptions& lidar, Scan* scan, DecodeStats* stats) {
  scan->points.reserve(uint64_t{cloud.height} * cloud.width);
  ForEachPoint(cloud, [&](const uint8_t* point) {
    LidarPoint p;
    const bool time_ok = ToAbsoluteNs(reader.Time(point), mapping, &p.t_ns);
    if (!KeepPoint(reader.X(point), reader.Y(point), reader.Z(point), time_ok, lidar, stats,
                   &p.p_lidar))
      return;
    if (reader.has_intensity()) {
      const double v = reader.Intensity(point);
      p.intensity = std::isfinite(v) && std::abs(v) < 1e30 ? float(v) : 0.0f;
    }
    if (reader.has_ring()) p.ring = ToRing(reader.Ring(point));
    scan->points.push_back(p);
  });
}

// Both passes (time range, then points) through one reader.
template <typename Reader>
Scan DecodeWith(const PointCloud2View& cloud, const Reader& reader, const Layout& layout,
                const LidarOptions& lidar, DecodeStats* stats) {
  const TimeRange range = ScanTimes(cloud, reader);
  const bool relative =
      layout.kind == TimeKind::kRelativeNs || layout.kind == TimeKind::kRelativeS;
  const TimeMapping mapping = relative
                                  ? RelativeMapping(cloud, range, lidar.header_stamp, stats)
                                  : AbsoluteMapping(cloud, layout, range, stats);
  Scan scan;
  DecodePoints(cloud, reader, mapping, lidar, &scan, stats);
  SetScanTimeBounds(cloud.header_stamp_ns, &scan);
  return scan;
}

bool Is(const FieldRef& f, uint8_t datatype) { return f.present && f.datatype == datatype; }

template <typename TimeT, bool kIntensity>
bool TryFastRing(const PointCloud2View& cloud, const Layout& layout, const PointFields& f,
                 const LidarOptions& lidar, DecodeStats* stats, Scan* scan) {
  if (!f.ring.present) {
    *scan = DecodeWith(cloud, FastReader<TimeT, kIntensity, Absent>(layout, f), layout, lidar, stats);
  } else if (f.ring.datatype == kPointUint16) {
    *scan = DecodeWith(cloud, FastReader<TimeT, kIntensity, uint16_t>(layout, f), layout, lidar, stats);
  } else if (f.ring.datatype == kPointUint8) {
    *scan = DecodeWith(cloud, FastReader<TimeT, kIntensity, uint8_t>(layout, f), layout, lidar, stats);
  } else {
    return false;
  }
  return true;
}

template <typename TimeT>
bool TryFastIntensity(const PointCloud2View& cloud, const Layout& layout, const PointFields& f,
                      const LidarOptions& lidar, DecodeStats* stats, Scan* scan) {
  if (!f.intensity.present) return TryFastRing<TimeT, false>(cloud, layout, f, lidar, stats, scan);
  if (Is(f.intensity, kPointFloat32) || Is(f.intensity, kPointUint16) ||
      Is(f.intensity, kPointUint8))
    return TryFastRing<TimeT, true>(cloud, layout, f, lidar, stats, scan);
  return false;
}

// The fast path: relative times in uint32 ns (Ouster `t`, Livox
// `offset_time`) or float32 s (Velodyne `time`), host byte order, float32
// x, y, z. False (nothing decoded)
// for any other layout, which then takes the generic reader.
bool TryFastDecode(const PointCloud2View& cloud, const Layout& layout, const PointFields& f,
                   const LidarOptions& lidar, DecodeStats* stats, Scan* scan) {
  if (cloud.is_bigendian != HostIsBigEndian()) return false;
  if (!Is(f.x, kPointFloat32) || !Is(f.y, kPointFloat32) || !Is(f.z, kPointFloat32)) return false;
  if (layout.kind == TimeKind::kRelativeNs && Is(layout.time, kPointUint32))
    return TryFastIntensity<uint32_t>(cloud, layout, f, lidar, stats, scan);
  if (layout.kind == TimeKind::kRelativeS && Is(layout.time, kPointFloat32))
    return TryFastIntensity<float>(cloud, layout, f, lidar, stats, scan);
  return false;
}

StatusOr<Scan> Decode(const PointCloud2View& cloud, const LidarOptions& lidar,
                      DecodeStats* stats_out, bool allow_fast) {
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

  stats->layout = layout->name;
  stats->raw_points = static_cast<int64_t>(uint64_t{cloud.height} * cloud.width);
  Scan scan;
  stats->fast_path = allow_fast && TryFastDecode(cloud, *layout, fields, lidar, stats, &scan);
  if (!stats->fast_path) {
    scan = DecodeWith(cloud, GenericReader(cloud, *layout, fields), *layout, lidar, stats);
  }
  scan.has_intensity = fields.intensity.present;
  scan.has_ring = fields.ring.present;
  return scan;
}

}  // namespace

bool FilterPoint(double x, double y, double z, bool time_ok, const LidarOptions& lidar,
                 DecodeStats* stats, Eigen::Vector3f* p_lidar) {
  return KeepPoint(x, y, z, time_ok, lidar, stats, p_lidar);
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
                                 DecodeStats* stats) {
  return Decode(cloud, lidar, stats, /*allow_fast=*/true);
}

StatusOr<Scan> DecodePointCloud2Generic(const PointCloud2View& cloud, const LidarOptions& lidar,
                                        DecodeStats* stats) {
  return Decode(cloud, lidar, stats, /*allow_fast=*/false);
}

}  // namespace rvlio

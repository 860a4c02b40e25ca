#include "rvlio/formats/las_writer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <ctime>
#include <limits>
#include <set>
#include <sstream>
#include <type_traits>

#include "rvlio/version.h"

namespace rvlio {
namespace {

// The ASPRS LAS 1.4 R15 layout (docs/outputs.md "map.las").
constexpr uint8_t kPointFormat = 6;
constexpr uint16_t kVlrHeaderSize = 54;
constexpr uint16_t kExtraBytesDescriptorSize = 192;
constexpr uint16_t kGlobalEncodingAdjustedGpsTime = 1u << 0;
constexpr uint16_t kGlobalEncodingWkt = 1u << 4;
constexpr uint8_t kExtraNoData = 1u << 0, kExtraMin = 1u << 1, kExtraMax = 1u << 2;
constexpr double kOffsetGrid_m = 1000.0;  // the default offset: a multiple of 1 km
constexpr double kGpsMinusUnix_s = 315964800.0;  // 1980-01-06 00:00:00 UTC in UNIX time
constexpr double kAdjustedGpsShift_s = 1e9;

// Little-endian field writers into a byte string at a fixed position.
template <typename T>
void Put(std::string* out, size_t at, T value) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::memcpy(&(*out)[at], &value, sizeof(T));  // the machine is little-endian (x86-64, arm64)
}
void PutText(std::string* out, size_t at, const std::string& text, size_t width) {
  std::memcpy(&(*out)[at], text.data(), std::min(text.size(), width));  // the rest stays 0
}

// One VLR: the 54-byte header and its payload.
std::string Vlr(const char* user_id, uint16_t record_id, const std::string& description,
                const std::string& payload) {
  std::string vlr(kVlrHeaderSize, '\0');
  PutText(&vlr, 2, user_id, 16);
  Put<uint16_t>(&vlr, 18, record_id);
  Put<uint16_t>(&vlr, 20, static_cast<uint16_t>(payload.size()));
  PutText(&vlr, 22, description, 32);
  return vlr + payload;
}

bool IsFloat(LasScalar t) { return t == LasScalar::kFloat || t == LasScalar::kDouble; }
bool IsSigned(LasScalar t) {
  return t == LasScalar::kInt8 || t == LasScalar::kInt16 || t == LasScalar::kInt32 ||
         t == LasScalar::kInt64;
}

// min/max/no_data of an extra field: "anytype", upcast to 8 bytes.
void PutAnyType(std::string* out, size_t at, LasScalar type, double value) {
  if (IsFloat(type)) Put<double>(out, at, value);
  else if (IsSigned(type)) Put<int64_t>(out, at, static_cast<int64_t>(value));
  else Put<uint64_t>(out, at, static_cast<uint64_t>(value));
}

// One value of an extra field: integers rounded and clamped to the type's
// range. Returns the value as stored (for the field's min and max).
template <typename T>
double PutValue(std::string* out, size_t at, double v) {
  if constexpr (std::is_floating_point_v<T>) {
    Put<T>(out, at, static_cast<T>(v));
    return static_cast<T>(v);
  } else {
    using L = std::numeric_limits<T>;
    const double r = std::isfinite(v) ? std::nearbyint(v) : 0.0;
    const T x = r <= static_cast<double>(L::min()) ? L::min()
                : r >= static_cast<double>(L::max()) ? L::max()
                                                      : static_cast<T>(r);
    Put<T>(out, at, x);
    return static_cast<double>(x);
  }
}

double PutExtraValue(std::string* out, size_t at, LasScalar type, double v) {
  switch (type) {
    case LasScalar::kUint8: return PutValue<uint8_t>(out, at, v);
    case LasScalar::kInt8: return PutValue<int8_t>(out, at, v);
    case LasScalar::kUint16: return PutValue<uint16_t>(out, at, v);
    case LasScalar::kInt16: return PutValue<int16_t>(out, at, v);
    case LasScalar::kUint32: return PutValue<uint32_t>(out, at, v);
    case LasScalar::kInt32: return PutValue<int32_t>(out, at, v);
    case LasScalar::kUint64: return PutValue<uint64_t>(out, at, v);
    case LasScalar::kInt64: return PutValue<int64_t>(out, at, v);
    case LasScalar::kFloat: return PutValue<float>(out, at, v);
    case LasScalar::kDouble: return PutValue<double>(out, at, v);
  }
  return v;
}

// UNIX times (UTC) at which GPS time gained a leap second over UTC since its
// origin: the first days of these months (IERS bulletins; none since 2017).
constexpr int kLeapSecondMonths[][2] = {
    {1981, 7}, {1982, 7}, {1983, 7}, {1985, 7}, {1988, 1}, {1990, 1},
    {1991, 1}, {1992, 7}, {1993, 7}, {1994, 7}, {1996, 1}, {1997, 7},
    {1999, 1}, {2006, 1}, {2009, 1}, {2012, 7}, {2015, 7}, {2017, 1}};

double UnixTimeOf(int year, int month) {
  std::tm tm{};
  tm.tm_year = year - 1900;
  tm.tm_mon = month - 1;
  tm.tm_mday = 1;
  return static_cast<double>(timegm(&tm));
}

Status OptionsError(const std::string& path, const std::string& what) {
  return Status::InvalidInput(path + ": " + what);
}

Status CheckOptions(const std::string& path, const LasWriterOptions& o) {
  if (o.offset_m) {
    if (!o.offset_m->allFinite()) return OptionsError(path, "LAS offset is not finite");
    for (int i = 0; i < 3; ++i) {
      const double steps = (*o.offset_m)[i] / LasWriter::kScale_m;
      if (std::abs(steps - std::nearbyint(steps)) > 1e-6)
        return OptionsError(path, "LAS offset is not a multiple of the 1 mm scale");
    }
  }
  if (!(o.intensity_scale >= 0.0) || !std::isfinite(o.intensity_scale))
    return OptionsError(path, "LAS intensity scale must be finite and >= 0");
  if (o.system_identifier.size() > 32 || o.generating_software.size() > 32)
    return OptionsError(path, "LAS system identifier and generating software hold 32 characters");
  if (o.crs_wkt.size() + 1 > std::numeric_limits<uint16_t>::max())
    return OptionsError(path, "the CRS's WKT is longer than a LAS VLR holds (65534 characters)");
  std::set<std::string> names;
  size_t bytes = LasWriter::kFormat6Size;
  for (const LasExtraField& f : o.extra_fields) {
    if (f.name.empty() || f.name.size() > 32)
      return OptionsError(path, "LAS extra-bytes field name '" + f.name.substr(0, 40) +
                                    "' must have 1 to 32 characters");
    if (f.description.size() > 32)
      return OptionsError(path, "description of LAS field " + f.name + " is over 32 characters");
    if (!names.insert(f.name).second)
      return OptionsError(path, "LAS extra-bytes field " + f.name + " given twice");
    bytes += LasScalarSize(f.type);
  }
  if (bytes > std::numeric_limits<uint16_t>::max() ||
      o.extra_fields.size() * kExtraBytesDescriptorSize > std::numeric_limits<uint16_t>::max())
    return OptionsError(path, "too many LAS extra-bytes fields (" +
                                  std::to_string(o.extra_fields.size()) + ")");
  return Status::Ok();
}

}  // namespace

int LasScalarSize(LasScalar type) {
  switch (type) {
    case LasScalar::kUint8: case LasScalar::kInt8: return 1;
    case LasScalar::kUint16: case LasScalar::kInt16: return 2;
    case LasScalar::kUint32: case LasScalar::kInt32: case LasScalar::kFloat: return 4;
    case LasScalar::kUint64: case LasScalar::kInt64: case LasScalar::kDouble: return 8;
  }
  return 0;
}

double UnixToAdjustedGpsTime(double unix_s) {
  static const std::vector<double> kLeapUnix_s = [] {  // computed once, thread-safe
    std::vector<double> t;
    for (const auto& m : kLeapSecondMonths) t.push_back(UnixTimeOf(m[0], m[1]));
    return t;
  }();
  const int leap = static_cast<int>(
      std::upper_bound(kLeapUnix_s.begin(), kLeapUnix_s.end(), unix_s) - kLeapUnix_s.begin());
  return unix_s - kGpsMinusUnix_s + leap - kAdjustedGpsShift_s;
}

Status LasWriter::Open(const std::string& path, LasWriterOptions options) {
  Discard();
  if (Status s = CheckOptions(path, options); !s.ok()) return s;
  options_ = std::move(options);
  if (options_.generating_software.empty())
    options_.generating_software = std::string("rvlio ") + RVLIO_VERSION;
  path_ = path;
  stats_ = LasWriteStats{};
  record_size_ = kFormat6Size;
  for (const LasExtraField& f : options_.extra_fields)
    record_size_ = static_cast<uint16_t>(record_size_ + LasScalarSize(f.type));
  record_.assign(record_size_, '\0');
  extra_min_.assign(options_.extra_fields.size(), std::numeric_limits<double>::infinity());
  extra_max_.assign(options_.extra_fields.size(), -std::numeric_limits<double>::infinity());
  min_i_.setConstant(std::numeric_limits<int64_t>::max());
  max_i_.setConstant(std::numeric_limits<int64_t>::min());
  offset_set_ = options_.offset_m.has_value();
  stats_.offset_m = offset_set_ ? *options_.offset_m : Eigen::Vector3d::Zero();
  const std::string vlrs = Vlrs();
  point_offset_ = static_cast<uint32_t>(kHeaderSize + vlrs.size());
  if (Status s = file_.Open(path); !s.ok()) return s;
  if (Status s = file_.Append(Header()); !s.ok()) return Fail(s);
  if (Status s = file_.Append(vlrs); !s.ok()) return Fail(s);
  return Status::Ok();
}

void LasWriter::SetOffset(const Eigen::Vector3d& first_m) {
  for (int i = 0; i < 3; ++i) stats_.offset_m[i] = std::floor(first_m[i] / kOffsetGrid_m) * kOffsetGrid_m;
  offset_set_ = true;
}

Status LasWriter::Write(const LasPoint& point) {
  RVLIO_CHECK_MSG(file_.is_open(), "LasWriter::Write before Open");
  if (!point.p_m.allFinite())
    return Fail(Status::InvalidInput(path_ + ": point " + std::to_string(stats_.points) +
                                     " has a non-finite coordinate"));
  if (!offset_set_) SetOffset(point.p_m);
  std::string& r = record_;
  for (int i = 0; i < 3; ++i) {
    const double steps = std::nearbyint((point.p_m[i] - stats_.offset_m[i]) / kScale_m);
    if (std::abs(steps) > std::numeric_limits<int32_t>::max())
      return Fail(Status::InvalidInput(
          path_ + ": point " + std::to_string(stats_.points) + " lies " +
          std::to_string(std::abs(point.p_m[i] - stats_.offset_m[i]) / 1000.0) +
          " km from the LAS offset along " + "xyz"[i] +
          ", beyond the 2147 km that 32-bit millimetres reach"));
    const int64_t v = static_cast<int64_t>(steps);
    min_i_[i] = std::min(min_i_[i], v);
    max_i_[i] = std::max(max_i_[i], v);
    Put<int32_t>(&r, 4 * i, static_cast<int32_t>(v));
  }
  double intensity = 0.0;
  if (options_.intensity_scale > 0.0) {
    intensity = std::nearbyint(point.intensity * options_.intensity_scale);
    if (!(intensity >= 0.0 && intensity <= 65535.0)) {  // NaN too
      ++stats_.intensity_clamped;
      intensity = intensity > 65535.0 ? 65535.0 : 0.0;
    }
  }
  Put<uint16_t>(&r, 12, static_cast<uint16_t>(intensity));
  Put<uint8_t>(&r, 14, 0x11);  // return 1 of 1
  int ring = options_.has_ring ? point.ring : 0;
  if (ring < 0 || ring > 255) {
    ++stats_.ring_saturated;
    ring = ring < 0 ? 0 : 255;
  }
  Put<uint8_t>(&r, 17, static_cast<uint8_t>(ring));  // 15, 16, 18, 19 stay 0
  Put<uint16_t>(&r, 20, options_.has_point_source ? static_cast<uint16_t>(point.scan_index % 65536)
                                                  : uint16_t{0});
  Put<double>(&r, 22, options_.has_time ? UnixToAdjustedGpsTime(point.unix_time_s) : 0.0);
  size_t at = kFormat6Size;
  for (size_t k = 0; k < options_.extra_fields.size(); ++k) {
    const LasScalar type = options_.extra_fields[k].type;
    const double v = PutExtraValue(&r, at, type, point.extra[k]);
    if (std::isfinite(v)) {
      extra_min_[k] = std::min(extra_min_[k], v);
      extra_max_[k] = std::max(extra_max_[k], v);
    }
    at += LasScalarSize(type);
  }
  ++stats_.points;
  if (Status s = file_.Append(r); !s.ok()) return Fail(s);
  return Status::Ok();
}

Status LasWriter::Commit() {
  RVLIO_CHECK_MSG(file_.is_open(), "LasWriter::Commit before Open");
  for (int i = 0; i < 3; ++i) {
    stats_.min_m[i] = stats_.points == 0 ? 0.0 : min_i_[i] * kScale_m + stats_.offset_m[i];
    stats_.max_m[i] = stats_.points == 0 ? 0.0 : max_i_[i] * kScale_m + stats_.offset_m[i];
  }
  if (Status s = file_.WriteAt(0, Header() + Vlrs()); !s.ok()) return Fail(s);
  if (Status s = file_.Commit(); !s.ok()) return Fail(s);
  return Status::Ok();
}

void LasWriter::Discard() { file_.Discard(); }

Status LasWriter::Fail(Status s) {
  Discard();
  return s;
}

std::string LasWriter::Header() const {
  std::string h(kHeaderSize, '\0');
  PutText(&h, 0, "LASF", 4);
  Put<uint16_t>(&h, 6, kGlobalEncodingAdjustedGpsTime | kGlobalEncodingWkt);
  Put<uint8_t>(&h, 24, 1);
  Put<uint8_t>(&h, 25, 4);
  PutText(&h, 26, options_.system_identifier, 32);
  PutText(&h, 58, options_.generating_software, 32);
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  Put<uint16_t>(&h, 90, static_cast<uint16_t>(utc.tm_yday + 1));
  Put<uint16_t>(&h, 92, static_cast<uint16_t>(utc.tm_year + 1900));
  Put<uint16_t>(&h, 94, kHeaderSize);
  Put<uint32_t>(&h, 96, point_offset_);
  Put<uint32_t>(&h, 100, static_cast<uint32_t>(options_.crs_wkt.empty() ? 1 : 2) +
                             (options_.extra_fields.empty() ? 0 : 1));
  Put<uint8_t>(&h, 104, kPointFormat);
  Put<uint16_t>(&h, 105, record_size_);
  // 107..130: the legacy counts stay 0 (point format 6 has no legacy form).
  for (int i = 0; i < 3; ++i) {
    Put<double>(&h, 131 + 8 * i, kScale_m);
    Put<double>(&h, 155 + 8 * i, stats_.offset_m[i]);
    Put<double>(&h, 179 + 16 * i, stats_.max_m[i]);
    Put<double>(&h, 187 + 16 * i, stats_.min_m[i]);
  }
  // 227..246: no waveform data, no EVLR.
  Put<uint64_t>(&h, 247, stats_.points);
  Put<uint64_t>(&h, 255, stats_.points);  // all of them first returns
  return h;
}

std::string LasWriter::Description() const {
  std::ostringstream d;
  d << "rvlio map (" << options_.generating_software << "). Coordinates: metres, "
    << (options_.crs_wkt.empty() ? "a local frame (no CRS)" : "the CRS of the WKT record")
    << ", stored to 1 mm. Intensity: ";
  if (options_.intensity_scale > 0.0)
    d << options_.intensity_source << " x " << options_.intensity_scale
      << ", clamped to 0..65535.";
  else
    d << "none (0).";
  d << " GPS time: "
    << (options_.has_time ? "Adjusted Standard GPS Time of each point's acquisition."
                          : "none (0).")
    << " User data: " << (options_.has_ring ? "the LiDAR ring (beam), 255 for 255 and above."
                                           : "0.")
    << " Point source ID: "
    << (options_.has_point_source ? "the scan index modulo 65536 (extra bytes scan_index: all of it)."
                                  : "0.")
    << " Extra bytes: ";
  if (options_.extra_fields.empty()) d << "none.";
  for (size_t k = 0; k < options_.extra_fields.size(); ++k)
    d << (k > 0 ? ", " : "") << options_.extra_fields[k].name;
  if (!options_.extra_fields.empty()) d << " (float NaN: no value).";
  return d.str();
}

std::string LasWriter::Vlrs() const {
  std::string text = Description();
  text.push_back('\0');
  std::string out = Vlr("LASF_Spec", 3, "rvlio fields and conventions", text);
  if (!options_.crs_wkt.empty())
    out += Vlr("LASF_Projection", 2112, "OGC coordinate system WKT",
               options_.crs_wkt + std::string(1, '\0'));
  if (options_.extra_fields.empty()) return out;
  std::string eb(options_.extra_fields.size() * kExtraBytesDescriptorSize, '\0');
  for (size_t k = 0; k < options_.extra_fields.size(); ++k) {
    const LasExtraField& f = options_.extra_fields[k];
    const size_t at = k * kExtraBytesDescriptorSize;
    uint8_t flags = 0;
    Put<uint8_t>(&eb, at + 2, static_cast<uint8_t>(f.type));
    PutText(&eb, at + 4, f.name, 32);
    if (IsFloat(f.type)) {
      flags |= kExtraNoData;
      PutAnyType(&eb, at + 40, f.type, std::numeric_limits<double>::quiet_NaN());
    }
    if (extra_min_[k] <= extra_max_[k]) {  // some finite value was written
      flags |= kExtraMin | kExtraMax;
      PutAnyType(&eb, at + 64, f.type, extra_min_[k]);
      PutAnyType(&eb, at + 88, f.type, extra_max_[k]);
    }
    Put<uint8_t>(&eb, at + 3, flags);
    PutText(&eb, at + 160, f.description, 32);
  }
  return out + Vlr("LASF_Spec", 4, "extra bytes", eb);
}

}  // namespace rvlio

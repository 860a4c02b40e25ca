// The Ouster sensor metadata JSON (formats/ouster.h): the flat layout of firmware
// 2.x and the nested layout of firmware 3.x / SDK >= 0.8, read into one
// OusterMetadata; and the nested JSON written back for simulated captures.
#include <cmath>
#include <cstdio>
#include <utility>

#include <nlohmann/json.hpp>

#include "rvlio/formats/ouster.h"

namespace rvlio {
namespace {

using nlohmann::json;

struct ProfileName {
  const char* name;
  OusterLidarProfile profile;
};
constexpr ProfileName kProfiles[] = {
    {"LEGACY", OusterLidarProfile::kLegacy},
    {"RNG19_RFL8_SIG16_NIR16", OusterLidarProfile::kRng19Rfl8Sig16Nir16},
    {"RNG15_RFL8_NIR8", OusterLidarProfile::kRng15Rfl8Nir8},
    {"RNG19_RFL8_SIG16_NIR16_DUAL", OusterLidarProfile::kRng19Rfl8Sig16Nir16Dual},
    {"RNG15_RFL8_NIR8_DUAL", OusterLidarProfile::kRng15Rfl8Nir8Dual},
    {"FUSA_RNG15_RFL8_NIR8_DUAL", OusterLidarProfile::kFusaRng15Rfl8Nir8Dual},
};

// Reads JSON values with one error naming the metadata and the key.
class Reader {
 public:
  Reader(const json& root, std::string where) : root_(root), where_(std::move(where)) {}

  // The object at `section` (nested layout) or the root (flat layout).
  const json* Find(const std::string& section, const std::string& key) const {
    if (!section.empty()) {
      auto s = root_.find(section);
      if (s != root_.end() && s->is_object()) {
        auto it = s->find(key);
        if (it != s->end()) return &*it;
      }
    }
    auto it = root_.find(key);
    return it == root_.end() ? nullptr : &*it;
  }
  // The key in any of the sections, the first found.
  const json* FindAny(std::initializer_list<const char*> sections, const std::string& key) const {
    for (const char* s : sections) {
      if (const json* v = Find(s, key)) return v;
    }
    return Find("", key);
  }

  Status Missing(const std::string& key) const {
    return Status::InvalidInput("Ouster metadata '" + where_ + "' has no " + key);
  }
  Status Bad(const std::string& key, const std::string& why) const {
    return Status::InvalidInput("Ouster metadata '" + where_ + "': " + key + " " + why);
  }

  Status Number(const json* v, const std::string& key, double* out) const {
    if (v == nullptr) return Missing(key);
    if (!v->is_number() || !std::isfinite(v->get<double>())) return Bad(key, "is not a number");
    *out = v->get<double>();
    return Status::Ok();
  }
  Status Int(const json* v, const std::string& key, int64_t lo, int64_t hi, int64_t* out) const {
    double d = 0.0;
    if (Status s = Number(v, key, &d); !s.ok()) return s;
    if (d != std::floor(d) || d < static_cast<double>(lo) || d > static_cast<double>(hi))
      return Bad(key, "is not an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    *out = static_cast<int64_t>(d);
    return Status::Ok();
  }
  std::string Text(const json* v) const {
    if (v == nullptr) return "";
    if (v->is_string()) return v->get<std::string>();
    if (v->is_number_integer()) return std::to_string(v->get<int64_t>());
    return v->dump();
  }
  Status Numbers(const json* v, const std::string& key, size_t n, std::vector<double>* out) const {
    if (v == nullptr) return Missing(key);
    if (!v->is_array() || (n > 0 && v->size() != n))
      return Bad(key, n > 0 ? "is not an array of " + std::to_string(n) + " numbers"
                            : "is not an array of numbers");
    out->clear();
    for (const json& e : *v) {
      if (!e.is_number() || !std::isfinite(e.get<double>())) return Bad(key, "holds a non-number");
      out->push_back(e.get<double>());
    }
    return Status::Ok();
  }
  // A row-major 4x4 with its translation in mm -> an isometry in metres.
  Status Transform(const json* v, const std::string& key, Eigen::Isometry3d* out) const {
    std::vector<double> m;
    if (Status s = Numbers(v, key, 16, &m); !s.ok()) return s;
    Eigen::Matrix4d t;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) t(r, c) = m[4 * r + c];
    const Eigen::Matrix3d rot = t.topLeftCorner<3, 3>();
    if ((rot * rot.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-3 ||
        std::abs(rot.determinant() - 1.0) > 1e-3 || t.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
      return Bad(key, "is not a rigid transform (rotation not orthonormal or last row not 0 0 0 1)");
    out->setIdentity();
    out->linear() = rot;
    out->translation() = t.topRightCorner<3, 1>() * 1e-3;
    return Status::Ok();
  }

 private:
  const json& root_;
  std::string where_;
};

Status ParseMode(const Reader& r, OusterMetadata* m) {
  const json* mode = r.FindAny({"config_params"}, "lidar_mode");
  if (mode == nullptr) return r.Missing("lidar_mode");
  m->lidar_mode = r.Text(mode);
  int cols = 0, hz = 0;
  char tail = 0;
  if (std::sscanf(m->lidar_mode.c_str(), "%dx%d%c", &cols, &hz, &tail) != 2 || cols <= 0 ||
      cols > 8192 || hz <= 0 || hz > 100)
    return r.Bad("lidar_mode '" + m->lidar_mode + "'", "is not COLUMNSxRATE (e.g. 1024x10)");
  m->frequency_hz = hz;
  m->columns_per_frame = cols;
  return Status::Ok();
}

Status ParseProfile(const Reader& r, OusterMetadata* m) {
  if (const json* p = r.FindAny({"lidar_data_format", "data_format", "config_params"},
                                "udp_profile_lidar"))
    m->lidar_profile_name = r.Text(p);
  bool known = false;
  for (const ProfileName& p : kProfiles) {
    if (m->lidar_profile_name == p.name) {
      m->lidar_profile = p.profile;
      known = true;
    }
  }
  // Profiles rvlio knows but does not decode: the metadata is read (IMU
  // packets still decode) and the first lidar packet is refused.
  for (const char* undecoded : {"RNG19_RFL8_SIG16_NIR16_ZONE16", "RNG15_RFL8_NIR8_ZONE16"}) {
    if (m->lidar_profile_name == undecoded) {
      known = true;
      m->lidar_profile_decoded = false;
    }
  }
  if (!known)
    return r.Bad("udp_profile_lidar '" + m->lidar_profile_name + "'",
                 "is not a profile rvlio decodes (LEGACY, RNG19_RFL8_SIG16_NIR16, RNG15_RFL8_NIR8, "
                 "their _DUAL forms, FUSA_RNG15_RFL8_NIR8_DUAL)");
  if (const json* p = r.FindAny({"lidar_data_format", "data_format", "config_params"},
                                "udp_profile_imu"))
    m->imu_profile = r.Text(p);
  if (m->imu_profile == "ACCEL32_GYRO32_NMEA") {
    int64_t n = 0;
    if (Status s = r.Int(r.FindAny({"imu_data_format", "config_params"}, "imu_measurements_per_packet"),
                         "imu_measurements_per_packet", 1, 64, &n);
        !s.ok())
      return s;
    m->imu_measurements_per_packet = static_cast<int>(n);
  } else if (m->imu_profile != "LEGACY") {
    return r.Bad("udp_profile_imu '" + m->imu_profile + "'",
                 "is not an IMU profile rvlio decodes (LEGACY, ACCEL32_GYRO32_NMEA)");
  }
  if (const json* h = r.FindAny({"lidar_data_format", "config_params"}, "header_type"))
    m->header_type = r.Text(h);
  if (m->lidar_profile == OusterLidarProfile::kFusaRng15Rfl8Nir8Dual) m->header_type = "FUSA";
  if (m->header_type != "STANDARD" && m->header_type != "FUSA")
    return r.Bad("header_type '" + m->header_type + "'", "is not STANDARD or FUSA");
  return Status::Ok();
}

Status ParseDataFormat(const Reader& r, OusterMetadata* m) {
  const auto fmt = {"lidar_data_format", "data_format"};
  int64_t v = 0;
  if (const json* cols = r.FindAny(fmt, "columns_per_frame")) {
    if (Status s = r.Int(cols, "columns_per_frame", 1, 8192, &v); !s.ok()) return s;
    if (v != m->columns_per_frame)
      return r.Bad("columns_per_frame " + std::to_string(v), "disagrees with lidar_mode " + m->lidar_mode);
  }
  if (const json* cpp = r.FindAny(fmt, "columns_per_packet")) {
    if (Status s = r.Int(cpp, "columns_per_packet", 1, 64, &v); !s.ok()) return s;
    m->columns_per_packet = static_cast<int>(v);
  }
  m->pixels_per_column = static_cast<int>(m->beam_altitude_deg.size());
  if (const json* ppc = r.FindAny(fmt, "pixels_per_column")) {
    if (Status s = r.Int(ppc, "pixels_per_column", 1, 256, &v); !s.ok()) return s;
    if (v != m->pixels_per_column)
      return r.Bad("pixels_per_column " + std::to_string(v),
                   "disagrees with the " + std::to_string(m->pixels_per_column) + " beam angles");
  }
  m->column_first = 0;
  m->column_last = m->columns_per_frame - 1;
  if (const json* w = r.FindAny(fmt, "column_window")) {
    std::vector<double> win;
    if (Status s = r.Numbers(w, "column_window", 2, &win); !s.ok()) return s;
    for (double c : win) {
      if (c != std::floor(c) || c < 0 || c >= m->columns_per_frame)
        return r.Bad("column_window", "holds a column outside [0, " +
                                          std::to_string(m->columns_per_frame - 1) + "]");
    }
    m->column_first = static_cast<int>(win[0]);
    m->column_last = static_cast<int>(win[1]);
  }
  m->pixel_shift_by_row.assign(m->pixels_per_column, 0);
  if (const json* ps = r.FindAny(fmt, "pixel_shift_by_row")) {
    std::vector<double> shift;
    if (Status s = r.Numbers(ps, "pixel_shift_by_row", m->pixels_per_column, &shift); !s.ok())
      return s;
    for (size_t i = 0; i < shift.size(); ++i) m->pixel_shift_by_row[i] = static_cast<int>(shift[i]);
  }
  return Status::Ok();
}

Status ParseBeams(const Reader& r, OusterMetadata* m) {
  if (Status s = r.Numbers(r.FindAny({"beam_intrinsics"}, "beam_altitude_angles"),
                           "beam_altitude_angles", 0, &m->beam_altitude_deg);
      !s.ok())
    return s;
  const size_t beams = m->beam_altitude_deg.size();
  if (beams == 0 || beams > 256) return r.Bad("beam_altitude_angles", "holds no beam or more than 256");
  if (Status s = r.Numbers(r.FindAny({"beam_intrinsics"}, "beam_azimuth_angles"),
                           "beam_azimuth_angles", beams, &m->beam_azimuth_deg);
      !s.ok())
    return s;
  double origin_mm = 0.0;
  if (Status s = r.Number(r.FindAny({"beam_intrinsics"}, "lidar_origin_to_beam_origin_mm"),
                          "lidar_origin_to_beam_origin_mm", &origin_mm);
      !s.ok())
    return s;
  m->lidar_origin_to_beam_origin_m = origin_mm * 1e-3;
  // Without beam_to_lidar_transform (flat layout): the beam origin lies on
  // the lidar x axis at lidar_origin_to_beam_origin_mm.
  m->lidar_T_beam.setIdentity();
  m->lidar_T_beam.translation().x() = m->lidar_origin_to_beam_origin_m;
  if (const json* bt = r.FindAny({"beam_intrinsics"}, "beam_to_lidar_transform"))
    return r.Transform(bt, "beam_to_lidar_transform", &m->lidar_T_beam);
  return Status::Ok();
}

Status ParseTransforms(const Reader& r, OusterMetadata* m) {
  if (Status s = r.Transform(r.FindAny({"lidar_intrinsics"}, "lidar_to_sensor_transform"),
                             "lidar_to_sensor_transform", &m->sensor_T_lidar);
      !s.ok())
    return s;
  return r.Transform(r.FindAny({"imu_intrinsics"}, "imu_to_sensor_transform"),
                     "imu_to_sensor_transform", &m->sensor_T_imu);
}

Status ParseIdentity(const Reader& r, OusterMetadata* m) {
  m->prod_line = r.Text(r.FindAny({"sensor_info"}, "prod_line"));
  m->prod_sn = r.Text(r.FindAny({"sensor_info"}, "prod_sn"));
  m->firmware = r.Text(r.FindAny({"sensor_info"}, "build_rev"));
  m->image_rev = r.Text(r.FindAny({"sensor_info"}, "image_rev"));
  m->timestamp_mode = r.Text(r.FindAny({"config_params"}, "timestamp_mode"));
  int64_t v = 0;
  if (const json* id = r.FindAny({"sensor_info"}, "initialization_id")) {
    if (Status s = r.Int(id, "initialization_id", 0, (int64_t{1} << 24) - 1, &v); !s.ok()) return s;
    m->initialization_id = v;
  }
  if (const json* p = r.FindAny({"config_params"}, "udp_port_lidar")) {
    if (Status s = r.Int(p, "udp_port_lidar", 0, 65535, &v); !s.ok()) return s;
    m->udp_port_lidar = static_cast<int>(v);
  }
  if (const json* p = r.FindAny({"config_params"}, "udp_port_imu")) {
    if (Status s = r.Int(p, "udp_port_imu", 0, 65535, &v); !s.ok()) return s;
    m->udp_port_imu = static_cast<int>(v);
  }
  return Status::Ok();
}

json TransformJson(const Eigen::Isometry3d& T) {
  json out = json::array();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out.push_back(c == 3 && r < 3 ? T(r, c) * 1e3 : T(r, c));
  return out;
}

}  // namespace

const char* OusterLidarProfileName(OusterLidarProfile profile) {
  for (const ProfileName& p : kProfiles) {
    if (p.profile == profile) return p.name;
  }
  return "UNKNOWN";
}

int OusterMetadata::WindowColumns() const {
  return column_first <= column_last ? column_last - column_first + 1
                                     : columns_per_frame - column_first + column_last + 1;
}

bool OusterMetadata::InWindow(int measurement_id) const {
  if (column_first <= column_last)
    return measurement_id >= column_first && measurement_id <= column_last;
  return measurement_id >= column_first || measurement_id <= column_last;
}

StatusOr<OusterMetadata> ParseOusterMetadata(const std::string& json_text,
                                             const std::string& where) {
  json root = json::parse(json_text, nullptr, /*allow_exceptions=*/false);
  if (root.is_discarded() || !root.is_object())
    return Status::InvalidInput("Ouster metadata '" + where + "' is not a JSON object");
  const Reader r(root, where);
  OusterMetadata m;
  for (Status (*step)(const Reader&, OusterMetadata*) :
       {ParseMode, ParseProfile, ParseBeams, ParseDataFormat, ParseTransforms, ParseIdentity}) {
    if (Status s = step(r, &m); !s.ok()) return s;
  }
  return m;
}

std::string OusterMetadataJson(const OusterMetadata& m) {
  json root;
  root["sensor_info"] = {{"prod_line", m.prod_line},   {"prod_sn", m.prod_sn},
                         {"build_rev", m.firmware},    {"image_rev", m.image_rev},
                         {"initialization_id", m.initialization_id < 0 ? 0 : m.initialization_id}};
  root["config_params"] = {{"lidar_mode", m.lidar_mode},
                           {"udp_port_lidar", m.udp_port_lidar},
                           {"udp_port_imu", m.udp_port_imu},
                           {"udp_profile_lidar", m.lidar_profile_name},
                           {"udp_profile_imu", m.imu_profile},
                           {"timestamp_mode", m.timestamp_mode}};
  root["lidar_data_format"] = {{"columns_per_frame", m.columns_per_frame},
                               {"columns_per_packet", m.columns_per_packet},
                               {"pixels_per_column", m.pixels_per_column},
                               {"column_window", {m.column_first, m.column_last}},
                               {"pixel_shift_by_row", m.pixel_shift_by_row},
                               {"udp_profile_lidar", m.lidar_profile_name},
                               {"udp_profile_imu", m.imu_profile},
                               {"header_type", m.header_type}};
  root["beam_intrinsics"] = {{"beam_altitude_angles", m.beam_altitude_deg},
                             {"beam_azimuth_angles", m.beam_azimuth_deg},
                             {"beam_to_lidar_transform", TransformJson(m.lidar_T_beam)},
                             {"lidar_origin_to_beam_origin_mm", m.lidar_origin_to_beam_origin_m * 1e3}};
  root["lidar_intrinsics"] = {{"lidar_to_sensor_transform", TransformJson(m.sensor_T_lidar)}};
  root["imu_intrinsics"] = {{"imu_to_sensor_transform", TransformJson(m.sensor_T_imu)}};
  if (m.imu_profile != "LEGACY")
    root["imu_data_format"] = {{"imu_measurements_per_packet", m.imu_measurements_per_packet}};
  return root.dump(2) + "\n";
}

}  // namespace rvlio

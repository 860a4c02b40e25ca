// Ouster lidar and IMU UDP packets (formats/ouster.h), from the public packet
// format: little-endian words; a legacy column is
//   timestamp u64 ns | measurement id u16 | frame id u16 | encoder u32 |
//   per beam 12 bytes (range u32, low 20 bits mm; reflectivity, signal,
//   near-IR, unused u16) | status u32 (0xffffffff valid)
// and every other profile has a 32-byte packet header (STANDARD: packet type
// u16, frame id u16, init id u24, serial u40; FUSA: packet type u8, init id
// u24, frame id u32, ..., serial u40 at byte 11), 12-byte column headers
//   timestamp u64 ns | measurement id u16 | status u16 (bit 0 valid)
// then per beam the profile's channel block, and a 32-byte packet footer
// whose last 8 bytes hold a CRC-64 on firmware that writes one.
#include <cmath>
#include <algorithm>
#include <cstring>
#include <type_traits>

#include "rvlio/formats/ouster.h"
#include "rvlio/lidar/extrinsics.h"

namespace rvlio {
namespace {

constexpr double kStandardGravity = 9.80665;  // m/s^2 per g
constexpr double kDegToRad = M_PI / 180.0;

// Little-endian words assembled byte by byte (any host); floats through
// their bit pattern.
template <class T>
T Load(const uint8_t* p) {
  if constexpr (std::is_same_v<T, float>) {
    const uint32_t bits = Load<uint32_t>(p);
    float v;
    std::memcpy(&v, &bits, sizeof(v));
    return v;
  } else {
    T v = 0;
    for (size_t i = 0; i < sizeof(T); ++i) v = static_cast<T>(v | (static_cast<T>(p[i]) << (8 * i)));
    return v;
  }
}
template <class T>
void Store(uint8_t* p, T v) {
  if constexpr (std::is_same_v<T, float>) {
    uint32_t bits;
    std::memcpy(&bits, &v, sizeof(bits));
    Store<uint32_t>(p, bits);
  } else {
    for (size_t i = 0; i < sizeof(T); ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
  }
}

bool IsLegacy(const OusterMetadata& m) { return m.lidar_profile == OusterLidarProfile::kLegacy; }

// First return's range (mm) and reflectivity of one channel block.
void ReadPixel(OusterLidarProfile profile, const uint8_t* px, uint32_t* range_mm, uint8_t* refl) {
  switch (profile) {
    case OusterLidarProfile::kLegacy:
      *range_mm = Load<uint32_t>(px) & 0xFFFFFu;
      *refl = static_cast<uint8_t>(std::min<uint16_t>(Load<uint16_t>(px + 4), 255));
      return;
    case OusterLidarProfile::kRng19Rfl8Sig16Nir16:
    case OusterLidarProfile::kRng19Rfl8Sig16Nir16Dual:
      *range_mm = Load<uint32_t>(px) & 0x7FFFFu;
      *refl = px[4];
      return;
    case OusterLidarProfile::kRng15Rfl8Nir8:
    case OusterLidarProfile::kRng15Rfl8Nir8Dual:
    case OusterLidarProfile::kFusaRng15Rfl8Nir8Dual:
      *range_mm = (Load<uint16_t>(px) & 0x7FFFu) * 8u;  // 8 mm units
      *refl = px[2];
      return;
  }
}

void WritePixel(OusterLidarProfile profile, uint32_t range_mm, uint8_t refl, uint8_t* px) {
  switch (profile) {
    case OusterLidarProfile::kLegacy:
      Store<uint32_t>(px, range_mm & 0xFFFFFu);
      Store<uint16_t>(px + 4, refl);
      return;
    case OusterLidarProfile::kRng19Rfl8Sig16Nir16:
    case OusterLidarProfile::kRng19Rfl8Sig16Nir16Dual:
      Store<uint32_t>(px, range_mm & 0x7FFFFu);
      px[4] = refl;
      return;
    case OusterLidarProfile::kRng15Rfl8Nir8:
    case OusterLidarProfile::kRng15Rfl8Nir8Dual:
    case OusterLidarProfile::kFusaRng15Rfl8Nir8Dual:
      Store<uint16_t>(px, static_cast<uint16_t>((range_mm / 8u) & 0x7FFFu));
      px[2] = refl;
      return;
  }
}

int PixelBytes(OusterLidarProfile profile) {
  switch (profile) {
    case OusterLidarProfile::kLegacy:
    case OusterLidarProfile::kRng19Rfl8Sig16Nir16: return 12;
    case OusterLidarProfile::kRng19Rfl8Sig16Nir16Dual: return 16;
    case OusterLidarProfile::kRng15Rfl8Nir8: return 4;
    case OusterLidarProfile::kRng15Rfl8Nir8Dual:
    case OusterLidarProfile::kFusaRng15Rfl8Nir8Dual: return 8;
  }
  return 12;
}

// Packet header fields: frame id and init id by header layout.
void ReadHeader(const OusterMetadata& m, const uint8_t* p, OusterLidarPacket* out) {
  if (m.header_type == "FUSA") {
    out->init_id = Load<uint32_t>(p) >> 8;
    out->frame_id = Load<uint32_t>(p + 4);
  } else {
    out->frame_id = Load<uint16_t>(p + 2);
    out->init_id = Load<uint32_t>(p + 4) & 0xFFFFFFu;
  }
}

void WriteHeader(const OusterMetadata& m, const OusterLidarPacket& packet, uint8_t* p) {
  const uint32_t init = static_cast<uint32_t>(std::max<int64_t>(packet.init_id, 0)) & 0xFFFFFFu;
  if (m.header_type == "FUSA") {
    Store<uint32_t>(p, 0x1u | (init << 8));
    Store<uint32_t>(p + 4, packet.frame_id);
  } else {
    Store<uint16_t>(p, 0x1);
    Store<uint16_t>(p + 2, static_cast<uint16_t>(packet.frame_id));
    Store<uint32_t>(p + 4, init);
  }
}

}  // namespace

int OusterPacketFormat::ColumnBytes() const {
  return column_header_bytes + pixels_per_column * pixel_bytes + column_footer_bytes;
}
int OusterPacketFormat::PacketBytes() const {
  return packet_header_bytes + columns_per_packet * ColumnBytes() + packet_footer_bytes;
}

OusterPacketFormat OusterFormatOf(const OusterMetadata& meta) {
  OusterPacketFormat f;
  const bool legacy = IsLegacy(meta);
  f.packet_header_bytes = legacy ? 0 : 32;
  f.column_header_bytes = legacy ? 16 : 12;
  f.pixel_bytes = PixelBytes(meta.lidar_profile);
  f.column_footer_bytes = legacy ? 4 : 0;
  f.packet_footer_bytes = legacy ? 0 : 32;
  f.columns_per_packet = meta.columns_per_packet;
  f.pixels_per_column = meta.pixels_per_column;
  return f;
}

uint64_t OusterCrc64(const uint8_t* data, size_t size) {
  constexpr uint64_t kPolyReflected = 0xC96C5795D7870F42ull;  // 0x42F0E1EBA9EA3693 reflected
  uint64_t crc = ~uint64_t{0};
  for (size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int b = 0; b < 8; ++b) crc = (crc & 1u) ? (crc >> 1) ^ kPolyReflected : crc >> 1;
  }
  return ~crc;
}

StatusOr<OusterLidarPacket> DecodeOusterLidarPacket(const OusterMetadata& meta,
                                                    const uint8_t* data, size_t size,
                                                    const std::string& where) {
  const OusterPacketFormat f = OusterFormatOf(meta);
  if (size != static_cast<size_t>(f.PacketBytes()))
    return Status::InvalidInput(where + ": lidar packet of " + std::to_string(size) +
                                " bytes; the metadata (" + meta.lidar_mode + ", " +
                                meta.lidar_profile_name + ", " + std::to_string(meta.pixels_per_column) +
                                " beams) gives " + std::to_string(f.PacketBytes()));
  OusterLidarPacket out;
  const bool legacy = IsLegacy(meta);
  if (!legacy) {
    ReadHeader(meta, data, &out);
    const uint64_t stored = Load<uint64_t>(data + size - 8);
    out.crc_present = stored == OusterCrc64(data, size - 8);
  }
  out.columns.resize(f.columns_per_packet);
  for (int c = 0; c < f.columns_per_packet; ++c) {
    const uint8_t* col = data + f.packet_header_bytes + static_cast<size_t>(c) * f.ColumnBytes();
    OusterColumn& column = out.columns[c];
    column.t_ns = static_cast<TimeNs>(Load<uint64_t>(col));
    column.measurement_id = Load<uint16_t>(col + 8);
    if (legacy) {
      column.frame_id = Load<uint16_t>(col + 10);
      const uint8_t* status = col + f.column_header_bytes + f.pixels_per_column * f.pixel_bytes;
      column.valid = Load<uint32_t>(status) == 0xFFFFFFFFu;
      if (c == 0) out.frame_id = column.frame_id;
    } else {
      column.frame_id = out.frame_id;
      column.valid = (Load<uint16_t>(col + 10) & 0x1u) != 0;
    }
    if (column.measurement_id >= meta.columns_per_frame)
      return Status::InvalidInput(where + ": measurement id " + std::to_string(column.measurement_id) +
                                  " is outside the " + std::to_string(meta.columns_per_frame) +
                                  " columns of mode " + meta.lidar_mode +
                                  " (metadata of another mode?)");
    column.range_mm.resize(f.pixels_per_column);
    column.reflectivity.resize(f.pixels_per_column);
    const uint8_t* px = col + f.column_header_bytes;
    for (int b = 0; b < f.pixels_per_column; ++b, px += f.pixel_bytes)
      ReadPixel(meta.lidar_profile, px, &column.range_mm[b], &column.reflectivity[b]);
  }
  return out;
}

std::vector<uint8_t> EncodeOusterLidarPacket(const OusterMetadata& meta,
                                             const OusterLidarPacket& packet) {
  const OusterPacketFormat f = OusterFormatOf(meta);
  RVLIO_CHECK(static_cast<int>(packet.columns.size()) == f.columns_per_packet);
  std::vector<uint8_t> out(static_cast<size_t>(f.PacketBytes()), 0);
  const bool legacy = IsLegacy(meta);
  if (!legacy) WriteHeader(meta, packet, out.data());
  for (int c = 0; c < f.columns_per_packet; ++c) {
    const OusterColumn& column = packet.columns[c];
    RVLIO_CHECK(static_cast<int>(column.range_mm.size()) == f.pixels_per_column);
    uint8_t* col = out.data() + f.packet_header_bytes + static_cast<size_t>(c) * f.ColumnBytes();
    Store<uint64_t>(col, static_cast<uint64_t>(column.t_ns));
    Store<uint16_t>(col + 8, static_cast<uint16_t>(column.measurement_id));
    if (legacy) {
      Store<uint16_t>(col + 10, static_cast<uint16_t>(packet.frame_id));
      uint8_t* status = col + f.column_header_bytes + f.pixels_per_column * f.pixel_bytes;
      Store<uint32_t>(status, column.valid ? 0xFFFFFFFFu : 0u);
    } else {
      Store<uint16_t>(col + 10, column.valid ? 1 : 0);
    }
    uint8_t* px = col + f.column_header_bytes;
    for (int b = 0; b < f.pixels_per_column; ++b, px += f.pixel_bytes) {
      const uint8_t refl = column.reflectivity.empty() ? 0 : column.reflectivity[b];
      WritePixel(meta.lidar_profile, column.range_mm[b], refl, px);
    }
  }
  if (!legacy && packet.crc_present)
    Store<uint64_t>(out.data() + out.size() - 8, OusterCrc64(out.data(), out.size() - 8));
  return out;
}

StatusOr<OusterImuPacket> DecodeOusterImuPacket(const uint8_t* data, size_t size,
                                                const std::string& where) {
  if (size != static_cast<size_t>(kOusterLegacyImuPacketBytes))
    return Status::InvalidInput(where + ": IMU packet of " + std::to_string(size) +
                                " bytes, not the " + std::to_string(kOusterLegacyImuPacketBytes) +
                                " of the LEGACY IMU profile");
  OusterImuPacket p;
  p.sys_t_ns = static_cast<TimeNs>(Load<uint64_t>(data));
  p.accel_t_ns = static_cast<TimeNs>(Load<uint64_t>(data + 8));
  p.gyro_t_ns = static_cast<TimeNs>(Load<uint64_t>(data + 16));
  for (int i = 0; i < 3; ++i) {
    p.accel_g[i] = Load<float>(data + 24 + 4 * i);
    p.gyro_deg_s[i] = Load<float>(data + 36 + 4 * i);
  }
  return p;
}

std::vector<uint8_t> EncodeOusterImuPacket(const OusterImuPacket& p) {
  std::vector<uint8_t> out(kOusterLegacyImuPacketBytes, 0);
  Store<uint64_t>(out.data(), static_cast<uint64_t>(p.sys_t_ns));
  Store<uint64_t>(out.data() + 8, static_cast<uint64_t>(p.accel_t_ns));
  Store<uint64_t>(out.data() + 16, static_cast<uint64_t>(p.gyro_t_ns));
  for (int i = 0; i < 3; ++i) {
    Store<float>(out.data() + 24 + 4 * i, p.accel_g[i]);
    Store<float>(out.data() + 36 + 4 * i, p.gyro_deg_s[i]);
  }
  return out;
}

ImuSample OusterImuToSample(const OusterImuPacket& p) {
  ImuSample s;
  s.t_ns = p.gyro_t_ns;
  s.acc_imu = p.accel_g.cast<double>() * kStandardGravity;
  s.gyro_imu = p.gyro_deg_s.cast<double>() * kDegToRad;
  return s;
}

namespace {
// ACCEL32_GYRO32_NMEA layout (firmware >= 3.2), byte offsets.
constexpr int kImuHeaderBytes = 32, kImuNmeaBytes = 100, kImuBlockBytes = 36, kImuFooterBytes = 32;
constexpr int kImuBlockAccelOffset = 12, kImuBlockGyroOffset = 24;
}  // namespace

int OusterImuPacketBytes(const OusterMetadata& meta) {
  if (meta.imu_profile == "LEGACY") return kOusterLegacyImuPacketBytes;
  return kImuHeaderBytes + kImuNmeaBytes + meta.imu_measurements_per_packet * kImuBlockBytes +
         kImuFooterBytes;
}

StatusOr<std::vector<ImuSample>> DecodeOusterImuSamples(const OusterMetadata& meta,
                                                         const uint8_t* data, size_t size,
                                                         const std::string& where, bool* crc_ok) {
  *crc_ok = true;
  if (meta.imu_profile == "LEGACY") {
    StatusOr<OusterImuPacket> legacy = DecodeOusterImuPacket(data, size, where);
    if (!legacy.ok()) return legacy.status();
    return std::vector<ImuSample>{OusterImuToSample(*legacy)};
  }
  const size_t expected = static_cast<size_t>(OusterImuPacketBytes(meta));
  if (size != expected)
    return Status::InvalidInput(where + ": IMU packet of " + std::to_string(size) + " bytes, not the " +
                                std::to_string(expected) + " of the " + meta.imu_profile +
                                " profile with " + std::to_string(meta.imu_measurements_per_packet) +
                                " measurements per packet");
  *crc_ok = OusterCrc64(data, size - 8) == Load<uint64_t>(data + size - 8);
  std::vector<ImuSample> samples(static_cast<size_t>(meta.imu_measurements_per_packet));
  const uint8_t* block = data + kImuHeaderBytes + kImuNmeaBytes;
  for (ImuSample& s : samples) {
    s.t_ns = static_cast<TimeNs>(Load<uint64_t>(block));
    for (int i = 0; i < 3; ++i) {
      s.acc_imu[i] = Load<float>(block + kImuBlockAccelOffset + 4 * i);
      s.gyro_imu[i] = Load<float>(block + kImuBlockGyroOffset + 4 * i);
    }
    block += kImuBlockBytes;
  }
  return samples;
}

std::vector<uint8_t> EncodeOusterAccel32ImuPacket(const OusterMetadata& meta,
                                                  const std::vector<ImuSample>& samples) {
  RVLIO_CHECK(static_cast<int>(samples.size()) == meta.imu_measurements_per_packet);
  std::vector<uint8_t> out(static_cast<size_t>(OusterImuPacketBytes(meta)), 0);
  uint8_t* block = out.data() + kImuHeaderBytes + kImuNmeaBytes;
  for (const ImuSample& s : samples) {
    Store<uint64_t>(block, static_cast<uint64_t>(s.t_ns));
    for (int i = 0; i < 3; ++i) {
      Store<float>(block + kImuBlockAccelOffset + 4 * i, static_cast<float>(s.acc_imu[i]));
      Store<float>(block + kImuBlockGyroOffset + 4 * i, static_cast<float>(s.gyro_imu[i]));
    }
    block += kImuBlockBytes;
  }
  Store<uint64_t>(out.data() + out.size() - 8, OusterCrc64(out.data(), out.size() - 8));
  return out;
}

OusterImuPacket OusterImuPacketOf(const ImuSample& s) {
  OusterImuPacket p;
  p.sys_t_ns = p.accel_t_ns = p.gyro_t_ns = s.t_ns;
  p.accel_g = (s.acc_imu / kStandardGravity).cast<float>();
  p.gyro_deg_s = (s.gyro_imu / kDegToRad).cast<float>();
  return p;
}

StatusOr<OusterMetadata> SimulatedOusterMetadata(const std::vector<double>& altitude_deg,
                                                 int columns, int rate_hz,
                                                 const Eigen::Isometry3d& imu_T_lidar) {
  if (columns % 16 != 0 || columns <= 0)
    return Status::InvalidInput("an Ouster capture needs columns in multiples of 16 (lidar.columns " +
                                std::to_string(columns) + ")");
  OusterMetadata m;
  m.prod_line = "OS-SIM-" + std::to_string(altitude_deg.size());
  m.prod_sn = "0";
  m.firmware = "rvlio-simulate";
  m.image_rev = "rvlio-simulate";
  m.lidar_mode = std::to_string(columns) + "x" + std::to_string(rate_hz);
  m.columns_per_frame = columns;
  m.frequency_hz = rate_hz;
  m.pixels_per_column = static_cast<int>(altitude_deg.size());
  m.lidar_profile = OusterLidarProfile::kRng19Rfl8Sig16Nir16;
  m.lidar_profile_name = OusterLidarProfileName(m.lidar_profile);
  m.timestamp_mode = "TIME_FROM_INTERNAL_OSC";
  m.column_first = 0;
  m.column_last = columns - 1;
  m.beam_altitude_deg = altitude_deg;
  m.beam_azimuth_deg.assign(altitude_deg.size(), 0.0);
  m.pixel_shift_by_row.assign(altitude_deg.size(), 0);
  m.sensor_T_imu = imu_T_lidar.inverse();
  m.udp_port_lidar = 7502;
  m.udp_port_imu = 7503;
  m.initialization_id = 1;
  return m;
}

std::vector<OusterLidarPacket> OusterPacketsOfScan(const OusterMetadata& meta, const Scan& organized,
                                                   uint32_t frame_id) {
  const int rows = meta.pixels_per_column, cols = meta.columns_per_frame;
  RVLIO_CHECK(static_cast<int>(organized.points.size()) == rows * cols);
  const OusterBeamModel beams(meta);
  std::vector<OusterLidarPacket> packets(cols / meta.columns_per_packet);
  for (size_t k = 0; k < packets.size(); ++k) {
    OusterLidarPacket& p = packets[k];
    p.frame_id = frame_id;
    p.init_id = meta.initialization_id;
    p.crc_present = true;
    p.columns.resize(meta.columns_per_packet);
    for (int c = 0; c < meta.columns_per_packet; ++c) {
      const int col = static_cast<int>(k) * meta.columns_per_packet + c;
      OusterColumn& column = p.columns[c];
      column.measurement_id = col;
      column.frame_id = frame_id;
      column.valid = true;
      column.t_ns = organized.points[col].t_ns;
      column.range_mm.assign(rows, 0);
      column.reflectivity.assign(rows, 0);
      for (int r = 0; r < rows; ++r) {
        const LidarPoint& pt = organized.points[static_cast<size_t>(r) * cols + col];
        if (pt.p_lidar.isZero()) continue;
        const double range_m = beams.RangeTo(pt.p_lidar.cast<double>(), col, r);
        column.range_mm[r] = static_cast<uint32_t>(std::clamp(std::llround(range_m * 1e3), 0LL, 0x7FFFFLL));
        column.reflectivity[r] = static_cast<uint8_t>(std::clamp(std::lround(pt.intensity), 0L, 255L));
      }
    }
  }
  return packets;
}

Eigen::Isometry3d OusterImuTLidar(const OusterMetadata& meta) { return meta.sensor_T_imu.inverse(); }

// ---------------------------------------------------------------------------
// Beam geometry (the documented range -> xyz conversion): with encoder angle
// theta_e = 2 pi (1 - mid / W), beam azimuth theta_a = -2 pi azimuth_deg / 360,
// altitude phi = 2 pi altitude_deg / 360 and the beam origin (bx, 0, bz) of
// beam_to_lidar_transform (n = |(bx, bz)|):
//   x = (r - n) cos(theta_e + theta_a) cos(phi) + bx cos(theta_e)
//   y = (r - n) sin(theta_e + theta_a) cos(phi) + bx sin(theta_e)
//   z = (r - n) sin(phi) + bz
// in the lidar frame; then the sensor frame through lidar_to_sensor_transform.

OusterBeamModel::OusterBeamModel(const OusterMetadata& meta)
    : columns_(meta.columns_per_frame), sensor_T_lidar_(meta.sensor_T_lidar) {
  beam_offset_x_m_ = meta.lidar_T_beam.translation().x();
  beam_offset_z_m_ = meta.lidar_T_beam.translation().z();
  beam_origin_m_ = std::hypot(beam_offset_x_m_, beam_offset_z_m_);
  for (size_t b = 0; b < meta.beam_altitude_deg.size(); ++b) {
    altitude_rad_.push_back(meta.beam_altitude_deg[b] * kDegToRad);
    azimuth_rad_.push_back(-meta.beam_azimuth_deg[b] * kDegToRad);
  }
}

Eigen::Vector3d OusterBeamModel::PointInSensor(double range_m, int measurement_id, int beam) const {
  const double encoder = 2.0 * M_PI * (1.0 - static_cast<double>(measurement_id) / columns_);
  const double az = encoder + azimuth_rad_[beam];
  const double alt = altitude_rad_[beam];
  const double d = range_m - beam_origin_m_;
  const Eigen::Vector3d p_lidar(d * std::cos(az) * std::cos(alt) + beam_offset_x_m_ * std::cos(encoder),
                                d * std::sin(az) * std::cos(alt) + beam_offset_x_m_ * std::sin(encoder),
                                d * std::sin(alt) + beam_offset_z_m_);
  return sensor_T_lidar_ * p_lidar;
}

double OusterBeamModel::RangeTo(const Eigen::Vector3d& p_sensor, int measurement_id, int beam) const {
  const double encoder = 2.0 * M_PI * (1.0 - static_cast<double>(measurement_id) / columns_);
  const double az = encoder + azimuth_rad_[beam];
  const double alt = altitude_rad_[beam];
  const Eigen::Vector3d p_lidar = sensor_T_lidar_.inverse() * p_sensor;
  const Eigen::Vector3d origin(beam_offset_x_m_ * std::cos(encoder), beam_offset_x_m_ * std::sin(encoder),
                               beam_offset_z_m_);
  const Eigen::Vector3d dir(std::cos(az) * std::cos(alt), std::sin(az) * std::cos(alt), std::sin(alt));
  return beam_origin_m_ + dir.dot(p_lidar - origin);
}

// ---------------------------------------------------------------------------
// Frame assembly

bool OusterFrameAfter(uint32_t a, uint32_t b, bool wide) {
  if (wide) return b != a && static_cast<uint32_t>(b - a) < 0x80000000u;
  const uint16_t d = static_cast<uint16_t>(b - a);
  return d != 0 && d < 0x8000u;
}

OusterScanAssembler::OusterScanAssembler(const OusterMetadata& meta, const LidarOptions& lidar)
    : meta_(meta), lidar_(lidar), beams_(meta) {
  columns_.resize(meta.columns_per_frame);
}

// The frame id of the window a packet belongs to. A window that wraps past
// column 0 ([first, W-1] then [0, last]) spans two sensor frames (the frame
// id advances at column 0): its head columns 0..last belong to the window
// that began in the previous frame.
uint32_t OusterScanAssembler::WindowFrameId(const OusterLidarPacket& packet) const {
  if (meta_.column_first <= meta_.column_last) return packet.frame_id;
  for (const OusterColumn& c : packet.columns) {
    if (!c.valid || !meta_.InWindow(c.measurement_id)) continue;
    if (c.measurement_id > meta_.column_last) return packet.frame_id;
    const bool wide = meta_.header_type == "FUSA";
    return wide ? packet.frame_id - 1u : (packet.frame_id - 1u) & 0xFFFFu;
  }
  return packet.frame_id;
}

bool OusterScanAssembler::Add(const OusterLidarPacket& sensor_packet, Scan* out, DecodeStats* decode) {
  ++stats_.lidar_packets;
  OusterLidarPacket packet = sensor_packet;
  packet.frame_id = WindowFrameId(sensor_packet);
  const bool wide = meta_.header_type == "FUSA";
  const uint32_t newest = have_frame_ ? frame_id_ : last_delivered_;
  if ((have_frame_ || have_delivered_) && packet.frame_id != newest &&
      !OusterFrameAfter(newest, packet.frame_id, wide)) {
    ++stats_.late_packets;  // a frame before the one being assembled
    return false;
  }
  if (!have_frame_ && have_delivered_ && packet.frame_id == last_delivered_) {
    ++stats_.late_packets;  // the frame was delivered at its last column
    return false;
  }
  if (have_frame_ && packet.frame_id != frame_id_) {
    // A packet of the next frame: the current one lost its end.
    Deliver(out, decode);
    Insert(packet);
    return true;
  }
  Insert(packet);
  // The window's last column arrived: the frame is complete (or as
  // complete as it gets), deliver it now rather than at the next frame.
  for (const OusterColumn& c : packet.columns) {
    if (c.measurement_id == meta_.column_last) {
      Deliver(out, decode);
      return true;
    }
  }
  return false;
}

void OusterScanAssembler::Insert(const OusterLidarPacket& packet) {
  if (!have_frame_) {
    have_frame_ = true;
    frame_id_ = packet.frame_id;
  }
  for (const OusterColumn& c : packet.columns) {
    if (!c.valid || !meta_.InWindow(c.measurement_id)) continue;
    OusterColumn& slot = columns_[c.measurement_id];
    if (!slot.valid) ++columns_present_;
    slot = c;
  }
}

bool OusterScanAssembler::Flush(Scan* out, DecodeStats* decode) {
  if (!have_frame_) return false;
  Deliver(out, decode);
  return true;
}

void OusterScanAssembler::Deliver(Scan* out, DecodeStats* decode) {
  *decode = DecodeStats();
  decode->layout = "ouster_packets";
  out->points.clear();
  TimeNs first_column_ns = 0;
  bool any = false;
  // Window order: first..last, through column 0 when the window wraps.
  const int window_columns = meta_.WindowColumns();
  for (int k = 0; k < window_columns; ++k) {
    const int mid = (meta_.column_first + k) % meta_.columns_per_frame;
    OusterColumn& c = columns_[mid];
    if (!c.valid) continue;
    if (!any || c.t_ns < first_column_ns) first_column_ns = c.t_ns;
    any = true;
    for (int b = 0; b < meta_.pixels_per_column; ++b) {
      ++decode->raw_points;
      const double range_m = c.range_mm[b] * 1e-3;
      // Filtered as float32, as a PointCloud2 of the same points would be.
      const Eigen::Vector3f p = range_m > 0.0
                                    ? Eigen::Vector3f(beams_.PointInSensor(range_m, mid, b).cast<float>())
                                    : Eigen::Vector3f::Zero();
      LidarPoint point;
      if (!FilterPoint(p.x(), p.y(), p.z(), true, lidar_, decode, &point.p_lidar)) continue;
      point.intensity = c.reflectivity[b];
      point.t_ns = c.t_ns;
      point.ring = static_cast<uint16_t>(b);
      out->points.push_back(point);
    }
    c.valid = false;
  }
  const int missing = window_columns - columns_present_;
  if (missing > 0) {
    stats_.missing_columns += missing;
    ++stats_.incomplete_frames;
  }
  ++stats_.frames;
  SetScanTimeBounds(first_column_ns, out);
  out->has_intensity = true;  // the reflectivity channel
  out->has_ring = true;
  have_frame_ = false;
  have_delivered_ = true;
  last_delivered_ = frame_id_;
  columns_present_ = 0;
}

}  // namespace rvlio

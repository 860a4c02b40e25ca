#pragma once
// Ouster sensors' own recordings, free of ROS types: the sensor metadata JSON,
// lidar and IMU UDP packets, and the assembly of lidar packets into scans.
// Written from Ouster's public packet-format documentation (firmware user
// manual, "Sensor Data"); docs/input_formats.md describes the decoding and
// which profiles and firmware versions were checked on real captures.
//
// Frames: a point is computed in the Ouster *lidar* frame from its range and
// the beam intrinsics, then moved into the Ouster *sensor* frame by
// lidar_to_sensor_transform. rvlio's LiDAR frame is that sensor frame; the
// IMU frame is the Ouster IMU frame (imu_to_sensor_transform).
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"
#include "rvlio/common/types.h"
#include "rvlio/formats/pointcloud2.h"
#include "rvlio/lidar/extrinsics.h"
#include "rvlio/lidar/options.h"

namespace rvlio {

// udp_profile_lidar values rvlio decodes.
enum class OusterLidarProfile {
  kLegacy,                 // "LEGACY" (and metadata without a profile: firmware < 2.2)
  kRng19Rfl8Sig16Nir16,    // "RNG19_RFL8_SIG16_NIR16"
  kRng15Rfl8Nir8,          // "RNG15_RFL8_NIR8" (low data rate)
  kRng19Rfl8Sig16Nir16Dual,  // "RNG19_RFL8_SIG16_NIR16_DUAL" (first return used)
  kRng15Rfl8Nir8Dual,      // "RNG15_RFL8_NIR8_DUAL" (first return used)
  kFusaRng15Rfl8Nir8Dual,  // "FUSA_RNG15_RFL8_NIR8_DUAL" (first return used)
};
const char* OusterLidarProfileName(OusterLidarProfile profile);

// What the metadata JSON says, in both layouts: the flat one of firmware
// 2.x (beam_altitude_angles, data_format, lidar_mode at the top) and the
// nested one of firmware 3.x and the SDK >= 0.8 (beam_intrinsics,
// lidar_data_format, config_params, sensor_info, ...).
struct OusterMetadata {
  std::string prod_line;          // "OS-1-128"
  std::string prod_sn;            // serial number as written
  std::string firmware;           // build_rev, e.g. "v2.3.0"
  std::string image_rev;          // the firmware image name
  std::string lidar_mode;         // "1024x10"
  int columns_per_frame = 0;      // 1024
  int frequency_hz = 0;           // 10 (from lidar_mode)
  int pixels_per_column = 0;      // beams
  int columns_per_packet = 16;
  std::string lidar_profile_name = "LEGACY";
  OusterLidarProfile lidar_profile = OusterLidarProfile::kLegacy;
  // False for a lidar profile rvlio knows but does not decode (the _ZONE16
  // profiles of firmware 3.2): IMU packets decode, lidar packets are refused.
  bool lidar_profile_decoded = true;
  std::string imu_profile = "LEGACY";  // or "ACCEL32_GYRO32_NMEA"
  int imu_measurements_per_packet = 1;  // imu_data_format (ACCEL32_GYRO32_NMEA)
  // Packet header layout: "STANDARD" (16-bit frame id) or "FUSA" (32-bit
  // frame id): lidar_data_format.header_type, FUSA for the FUSA_ profile.
  std::string header_type = "STANDARD";
  std::string timestamp_mode;     // config_params.timestamp_mode when present
  int column_first = 0, column_last = 0;  // column_window, inclusive (may wrap)
  std::vector<double> beam_altitude_deg, beam_azimuth_deg;
  std::vector<int> pixel_shift_by_row;  // staggered -> destaggered image shift
  // Transforms with translations in metres (the JSON holds millimetres).
  Eigen::Isometry3d sensor_T_lidar = Eigen::Isometry3d::Identity();  // lidar_to_sensor_transform
  Eigen::Isometry3d lidar_T_beam = Eigen::Isometry3d::Identity();    // beam_to_lidar_transform
  Eigen::Isometry3d sensor_T_imu = Eigen::Isometry3d::Identity();    // imu_to_sensor_transform
  double lidar_origin_to_beam_origin_m = 0.0;
  int udp_port_lidar = 0, udp_port_imu = 0;  // 0: not given
  int64_t initialization_id = -1;            // -1: not given

  // Columns the sensor sends per frame (the column window's size).
  int WindowColumns() const;
  bool InWindow(int measurement_id) const;
};

// InvalidInput naming `where` for text that is not JSON, lacks a field
// decoding needs, or holds inconsistent values (beam tables of another
// length than pixels_per_column, a lidar_mode that is not COLSxRATE, an
// unknown lidar or IMU profile).
StatusOr<OusterMetadata> ParseOusterMetadata(const std::string& json_text,
                                             const std::string& where);
// ParseOusterMetadata of a file's text; InvalidInput when it cannot be read.
StatusOr<OusterMetadata> ReadOusterMetadataFile(const std::string& path);
// The nested-layout JSON of `meta` (what `rvlio simulate --format ouster-pcap`
// writes next to its capture); ParseOusterMetadata reads it back exactly.
std::string OusterMetadataJson(const OusterMetadata& meta);

// Byte sizes of one lidar packet of a metadata's profile and beam count.
struct OusterPacketFormat {
  int packet_header_bytes = 0;  // 0 legacy, 32
  int column_header_bytes = 16;  // 16 legacy (ts, mid, fid, encoder), 12
  int pixel_bytes = 12;
  int column_footer_bytes = 4;  // legacy column status word, else 0
  int packet_footer_bytes = 0;  // 0 legacy, 32 (CRC-64 in its last 8 bytes where present)
  int columns_per_packet = 16;
  int pixels_per_column = 0;
  int ColumnBytes() const;
  int PacketBytes() const;
};
OusterPacketFormat OusterFormatOf(const OusterMetadata& meta);
constexpr int kOusterLegacyImuPacketBytes = 48;

// One column of a lidar packet: its time, its place in the frame and the
// first return's range of each beam (mm; 0 = no return).
struct OusterColumn {
  TimeNs t_ns = 0;
  int measurement_id = 0;
  uint32_t frame_id = 0;
  bool valid = false;
  std::vector<uint32_t> range_mm;
  std::vector<uint8_t> reflectivity;
};

struct OusterLidarPacket {
  uint32_t frame_id = 0;
  int64_t init_id = -1;    // -1: legacy packets carry none
  bool crc_present = false;  // the footer holds the CRC-64 of the packet
  std::vector<OusterColumn> columns;
};

// CRC-64/XZ (ECMA-182 polynomial, reflected, initial value and final xor
// all ones): what firmware >= 3.1 writes in a lidar packet's last 8 bytes.
uint64_t OusterCrc64(const uint8_t* data, size_t size);

// InvalidInput (naming `where`) when the size is not the format's; a
// measurement id outside the frame is InvalidInput too (another mode).
StatusOr<OusterLidarPacket> DecodeOusterLidarPacket(const OusterMetadata& meta,
                                                    const uint8_t* data, size_t size,
                                                    const std::string& where);
// Inverse of DecodeOusterLidarPacket for the profile of `meta` (every
// column's frame id must be packet.frame_id); appends a CRC-64 footer when
// packet.crc_present. Used by the simulator and the tests.
std::vector<uint8_t> EncodeOusterLidarPacket(const OusterMetadata& meta,
                                             const OusterLidarPacket& packet);

// A legacy IMU packet (48 bytes: diagnostic, accelerometer and gyroscope read
// times in ns, then accel x y z in g and gyro x y z in deg/s, float32).
struct OusterImuPacket {
  TimeNs sys_t_ns = 0, accel_t_ns = 0, gyro_t_ns = 0;
  Eigen::Vector3f accel_g = Eigen::Vector3f::Zero();
  Eigen::Vector3f gyro_deg_s = Eigen::Vector3f::Zero();
};
StatusOr<OusterImuPacket> DecodeOusterImuPacket(const uint8_t* data, size_t size,
                                                const std::string& where);
std::vector<uint8_t> EncodeOusterImuPacket(const OusterImuPacket& packet);
// Bytes of one IMU packet of the metadata's IMU profile: 48 for LEGACY;
// for ACCEL32_GYRO32_NMEA the 32-byte packet header, a 100-byte NMEA block,
// imu_measurements_per_packet blocks of 36 bytes and the 32-byte footer
// (CRC-64 in its last 8 bytes).
int OusterImuPacketBytes(const OusterMetadata& meta);
// The IMU samples of one packet in SI units, oldest first: one for LEGACY
// (OusterImuToSample), imu_measurements_per_packet for ACCEL32_GYRO32_NMEA.
// An ACCEL32_GYRO32_NMEA measurement block: sensor time (u64 ns), a 32-bit
// status word (not interpreted), accelerometer x y z (float32, m/s^2) and
// gyroscope x y z (float32, rad/s) -- SI units in this profile, unlike
// LEGACY's g and deg/s (docs/input_formats.md gives the evidence from a real
// capture). *crc_ok is false when the footer's CRC-64 does not match
// (ACCEL32_GYRO32_NMEA only). InvalidInput (naming `where`) for another size.
StatusOr<std::vector<ImuSample>> DecodeOusterImuSamples(const OusterMetadata& meta,
                                                         const uint8_t* data, size_t size,
                                                         const std::string& where, bool* crc_ok);
// Inverse of DecodeOusterImuSamples for ACCEL32_GYRO32_NMEA (exactly
// imu_measurements_per_packet samples; header, NMEA block and status zero;
// CRC-64 footer). Used by the tests.
std::vector<uint8_t> EncodeOusterAccel32ImuPacket(const OusterMetadata& meta,
                                                  const std::vector<ImuSample>& samples);
// SI units (standard gravity 9.80665 m/s^2 per g), stamped at the gyroscope
// read time (the accelerometer is read within microseconds of it).
ImuSample OusterImuToSample(const OusterImuPacket& packet);

// The Ouster IMU pose in the sensor frame as rvlio's extrinsic imu_T_lidar
// (rvlio's LiDAR frame = the Ouster sensor frame): inverse(sensor_T_imu).
Eigen::Isometry3d OusterImuTLidar(const OusterMetadata& meta);

// Beam geometry of one metadata, precomputed: range + (column, beam) ->
// point in the sensor frame (metres).
class OusterBeamModel {
 public:
  explicit OusterBeamModel(const OusterMetadata& meta);
  Eigen::Vector3d PointInSensor(double range_m, int measurement_id, int beam) const;
  // The range (m) at which (measurement_id, beam) gives p_sensor's direction
  // from the beam origin: the inverse used by the simulator.
  double RangeTo(const Eigen::Vector3d& p_sensor, int measurement_id, int beam) const;

 private:
  int columns_ = 0;
  Eigen::Isometry3d sensor_T_lidar_;
  double beam_offset_x_m_ = 0.0, beam_offset_z_m_ = 0.0, beam_origin_m_ = 0.0;
  std::vector<double> altitude_rad_, azimuth_rad_;
};

// What the assembly counted.
struct OusterFrameStats {
  int64_t frames = 0;            // frames delivered
  int64_t lidar_packets = 0;
  int64_t imu_packets = 0;
  int64_t missing_columns = 0;   // window columns absent or invalid in delivered frames
  int64_t incomplete_frames = 0;  // delivered frames with missing columns
  int64_t late_packets = 0;      // packets of a frame already delivered (dropped)
  int64_t crc_errors = 0;        // packets whose CRC-64 did not match (dropped)
  int64_t imu_crc_errors = 0;    // IMU packets whose CRC-64 did not match (dropped)
};

// Assembles lidar packets into scans: a frame is delivered when the packet
// holding the column window's last column arrives, or when a packet of a
// later frame id arrives (the frame lost its end), or at Flush. A window
// that wraps past column 0 (column_window [first, last], first > last) is
// one scan of columns first..W-1 of one sensor frame and 0..last of the
// next, in that order (times increasing). Columns keep their place by
// measurement id, so a lost packet leaves a gap (counted), never a shifted
// frame; a packet of an older frame is dropped and counted. Points: every
// beam with a return, range-cropped and filtered as DecodePointCloud2 does,
// each with its column's time; ring = beam index.
class OusterScanAssembler {
 public:
  OusterScanAssembler(const OusterMetadata& meta, const LidarOptions& lidar);
  // Adds one decoded packet; true and *out filled when it completed a frame.
  bool Add(const OusterLidarPacket& packet, Scan* out, DecodeStats* decode);
  // The last frame, if any columns are pending.
  bool Flush(Scan* out, DecodeStats* decode);
  const OusterFrameStats& stats() const { return stats_; }
  OusterFrameStats& mutable_stats() { return stats_; }

 private:
  uint32_t WindowFrameId(const OusterLidarPacket& packet) const;
  void Insert(const OusterLidarPacket& packet);
  void Deliver(Scan* out, DecodeStats* decode);

  OusterMetadata meta_;
  LidarOptions lidar_;
  OusterBeamModel beams_;
  OusterFrameStats stats_;
  bool have_frame_ = false;
  uint32_t frame_id_ = 0;
  bool have_delivered_ = false;
  uint32_t last_delivered_ = 0;
  std::vector<OusterColumn> columns_;  // by measurement id; valid = present
  int columns_present_ = 0;
};

// A simulated sensor as Ouster metadata (what `rvlio simulate --format
// ouster-pcap` writes): `altitude_deg` per row (row 0 = top), `columns` per
// frame at `rate_hz`, profile RNG19_RFL8_SIG16_NIR16 (ranges in mm), no beam
// azimuth offsets or beam origin offset, lidar_to_sensor = identity (the
// simulated LiDAR frame is the sensor frame), imu_to_sensor = inverse of
// `imu_T_lidar`. InvalidInput when columns is not a multiple of 16.
StatusOr<OusterMetadata> SimulatedOusterMetadata(const std::vector<double>& altitude_deg,
                                                 int columns, int rate_hz,
                                                 const Eigen::Isometry3d& imu_T_lidar);
// The lidar packets of one organized scan (rows x cols, index row * cols +
// col, zero point = no return, every point stamped with its column time):
// range = the point's distance from the beam origin rounded to mm,
// reflectivity = intensity clamped to [0, 255]. Column k's packet carries
// columns 16k..16k+15.
std::vector<OusterLidarPacket> OusterPacketsOfScan(const OusterMetadata& meta, const Scan& organized,
                                                   uint32_t frame_id);
// The IMU packet of a sample: its time in all three stamps, the
// accelerometer in g and the gyroscope in deg/s as float32 (the packet's
// quantization; OusterImuToSample inverts the units).
OusterImuPacket OusterImuPacketOf(const ImuSample& sample);

// The frame id `b` is after `a` (16-bit or 32-bit wrap-around: half the
// range ahead counts as later).
bool OusterFrameAfter(uint32_t a, uint32_t b, bool wide);

}  // namespace rvlio

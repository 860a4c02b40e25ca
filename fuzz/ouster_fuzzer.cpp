// libFuzzer target: pcap captures (formats/pcap.h) of Ouster packets (formats/ouster.h).
//
// Input: byte 0 picks the sensor (bits 0-2: lidar profile, bits 3-4: 32, 64
// or 128 beams; 1024x10, the packet sizes of the real captures), the rest is
// the capture file. Every UDP datagram goes to the lidar or IMU packet
// decoder (by size, else both), decoded lidar packets to the frame
// assembler; a datagram to port 9999 is parsed as metadata JSON.
//
// Invariants: no crash, no huge allocation (ASan/rss limits); every failure
// is InvalidInput with a one-line message naming the capture or packet; a
// failing reader keeps returning its error; an assembled frame never holds
// more points than its columns x beams, and its points carry the times of
// columns that were delivered.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "rvlio/formats/ouster.h"
#include "rvlio/formats/pcap.h"

namespace {

using rvlio::Status;

[[noreturn]] void Fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "ouster fuzzer invariant violated: %s\n%s\n", what, detail.c_str());
  std::abort();
}

void CheckError(const Status& s, const char* name) {
  if (s.code() != rvlio::StatusCode::kInvalidInput || s.message().empty())
    Fail("a failure is not InvalidInput with a message", s.message());
  if (s.message().find(name) == std::string::npos) Fail("an error does not name its input", s.message());
  if (s.message().find('\n') != std::string::npos) Fail("a multi-line error", s.message());
}

rvlio::OusterMetadata Sensor(uint8_t pick) {
  const rvlio::OusterLidarProfile profiles[] = {
      rvlio::OusterLidarProfile::kRng15Rfl8Nir8,         rvlio::OusterLidarProfile::kRng19Rfl8Sig16Nir16,
      rvlio::OusterLidarProfile::kFusaRng15Rfl8Nir8Dual, rvlio::OusterLidarProfile::kLegacy,
      rvlio::OusterLidarProfile::kRng19Rfl8Sig16Nir16Dual, rvlio::OusterLidarProfile::kRng15Rfl8Nir8Dual};
  const int beams[] = {128, 32, 64, 128};
  std::vector<double> altitude;
  const int n = beams[(pick >> 3) & 3];
  for (int b = 0; b < n; ++b) altitude.push_back(22.5 - 45.0 * b / (n - 1));
  auto meta = rvlio::SimulatedOusterMetadata(altitude, 1024, 10, Eigen::Isometry3d::Identity());
  if (!meta.ok()) Fail("simulated metadata rejected", meta.status().message());
  rvlio::OusterMetadata m = *meta;
  m.lidar_profile = profiles[(pick & 7) % 6];
  m.lidar_profile_name = rvlio::OusterLidarProfileName(m.lidar_profile);
  m.header_type = m.lidar_profile == rvlio::OusterLidarProfile::kFusaRng15Rfl8Nir8Dual ? "FUSA" : "STANDARD";
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const rvlio::OusterMetadata meta = Sensor(data[0]);
  const size_t lidar_bytes = static_cast<size_t>(rvlio::OusterFormatOf(meta).PacketBytes());
  auto reader = rvlio::PcapReader::OpenBuffer(
      std::string(reinterpret_cast<const char*>(data + 1), size - 1), "fuzz.pcap");
  if (!reader.ok()) {
    CheckError(reader.status(), "'fuzz.pcap'");
    return 0;
  }
  rvlio::LidarOptions lidar;
  lidar.min_range = 0.0;
  rvlio::OusterScanAssembler assembler(meta, lidar);
  rvlio::UdpDatagram d;
  rvlio::Scan scan;
  rvlio::DecodeStats decode;
  const size_t max_points = static_cast<size_t>(meta.columns_per_frame) * meta.pixels_per_column;
  auto check_scan = [&] {
    if (scan.points.size() > max_points) Fail("a frame with more points than pixels", "");
    for (const rvlio::LidarPoint& p : scan.points)
      if (p.t_ns < scan.t_start_ns || p.t_ns > scan.t_end_ns) Fail("a point outside its scan's time span", "");
  };
  for (int i = 0; i < 10000; ++i) {
    auto got = reader->Next(&d);
    if (!got.ok()) {
      CheckError(got.status(), "'fuzz.pcap'");
      auto again = reader->Next(&d);
      if (again.ok() || again.status().message() != got.status().message())
        Fail("a failing reader did not repeat its error", got.status().message());
      break;
    }
    if (!*got) break;
    if (d.dst_port == 9999) {
      auto m = rvlio::ParseOusterMetadata(std::string(d.payload.begin(), d.payload.end()), "fuzz.json");
      if (!m.ok()) CheckError(m.status(), "fuzz.json");
      continue;
    }
    if (d.payload.size() != lidar_bytes) {
      auto imu = rvlio::DecodeOusterImuPacket(d.payload.data(), d.payload.size(), "imu packet");
      if (!imu.ok()) CheckError(imu.status(), "imu packet");
      rvlio::OusterMetadata accel32;
      accel32.imu_profile = "ACCEL32_GYRO32_NMEA";
      accel32.imu_measurements_per_packet = 1 + static_cast<int>(d.payload.size() % 8);
      bool crc_ok = true;
      auto samples = rvlio::DecodeOusterImuSamples(accel32, d.payload.data(), d.payload.size(),
                                                   "imu packet", &crc_ok);
      if (!samples.ok()) CheckError(samples.status(), "imu packet");
    }
    auto packet = rvlio::DecodeOusterLidarPacket(meta, d.payload.data(), d.payload.size(), "lidar packet");
    if (!packet.ok()) {
      CheckError(packet.status(), "lidar packet");
      continue;
    }
    if (assembler.Add(*packet, &scan, &decode)) check_scan();
  }
  if (assembler.Flush(&scan, &decode)) check_scan();
  return 0;
}

// Ouster packet encoding and decoding, frame assembly with lost and late
// packets, the beam model, the CRC, and pcap writing and reading (IPv4
// fragments) on synthetic packets.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "rvlio/formats/ouster.h"
#include "rvlio/formats/pcap.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

OusterMetadata RealMetadata(const std::string& name) {
  const std::string path = std::string(RVLIO_TEST_DATA) + "/ouster/" + name;
  StatusOr<OusterMetadata> m = ParseOusterMetadata(ReadText(path), path);
  EXPECT_TRUE(m.ok()) << m.status().message();
  return m.ok() ? *m : OusterMetadata();
}

OusterMetadata WithProfile(OusterMetadata m, OusterLidarProfile p) {
  m.lidar_profile = p;
  m.lidar_profile_name = OusterLidarProfileName(p);
  m.header_type = p == OusterLidarProfile::kFusaRng15Rfl8Nir8Dual ? "FUSA" : "STANDARD";
  return m;
}

// Packet `k` of frame `frame`: columns 16k..16k+15, ranges that depend on
// column and beam (multiples of 8 mm: exact in every profile).
OusterLidarPacket MakePacket(const OusterMetadata& m, uint32_t frame, int k, TimeNs t0_ns) {
  OusterLidarPacket p;
  p.frame_id = frame;
  p.init_id = m.initialization_id;
  p.crc_present = true;
  for (int c = 0; c < m.columns_per_packet; ++c) {
    OusterColumn col;
    col.measurement_id = k * m.columns_per_packet + c;
    col.frame_id = frame;
    col.t_ns = t0_ns + col.measurement_id * 97656;
    col.valid = true;
    for (int b = 0; b < m.pixels_per_column; ++b) {
      col.range_mm.push_back(b % 7 == 0 ? 0u : static_cast<uint32_t>(8 * (250 + 3 * b + col.measurement_id)));
      col.reflectivity.push_back(static_cast<uint8_t>(b));
    }
    p.columns.push_back(col);
  }
  return p;
}

TEST(OusterMetadataTest, FlatAndNestedLayouts) {
  const OusterMetadata flat = RealMetadata("OS-1-128_v2.3.0_1024x10.json");
  EXPECT_EQ(flat.prod_line, "OS-1-128");
  EXPECT_EQ(flat.firmware, "v2.3.0");
  EXPECT_EQ(flat.columns_per_frame, 1024);
  EXPECT_EQ(flat.frequency_hz, 10);
  EXPECT_EQ(flat.pixels_per_column, 128);
  EXPECT_EQ(flat.lidar_profile, OusterLidarProfile::kRng15Rfl8Nir8);
  EXPECT_EQ(flat.pixel_shift_by_row.size(), 128u);
  EXPECT_DOUBLE_EQ(flat.beam_altitude_deg[0], 20.95);
  EXPECT_NEAR(flat.sensor_T_lidar.translation().z(), 0.03618, 1e-12);
  EXPECT_NEAR(flat.lidar_T_beam.translation().x(), 0.015806, 1e-12);
  EXPECT_NEAR(flat.sensor_T_lidar.linear()(0, 0), -1.0, 1e-12);
  EXPECT_NEAR(flat.sensor_T_imu.translation().x(), 0.006253, 1e-12);
  EXPECT_EQ(flat.udp_port_lidar, 7502);
  EXPECT_EQ(flat.WindowColumns(), 1024);

  const OusterMetadata nested = RealMetadata("windowed_frame1_0.json");
  EXPECT_EQ(nested.columns_per_frame, 512);
  EXPECT_EQ(nested.column_first, 1);
  EXPECT_EQ(nested.column_last, 256);
  EXPECT_EQ(nested.WindowColumns(), 256);
  EXPECT_FALSE(nested.InWindow(0));
  EXPECT_TRUE(nested.InWindow(256));
  EXPECT_EQ(nested.udp_port_lidar, 53750);

  const OusterMetadata fusa = RealMetadata("OS-1-128_767798045_1024x10_20230712_120049.json");
  EXPECT_EQ(fusa.lidar_profile, OusterLidarProfile::kFusaRng15Rfl8Nir8Dual);
  EXPECT_EQ(fusa.header_type, "FUSA");
  EXPECT_EQ(fusa.initialization_id, 390076);

  const OusterMetadata old = RealMetadata("OS-1-32-G_v2.1.1_1024x10.json");  // no profile: legacy
  EXPECT_EQ(old.lidar_profile, OusterLidarProfile::kLegacy);
  EXPECT_EQ(old.pixels_per_column, 32);
}

TEST(OusterMetadataTest, WrittenJsonReadsBackExactly) {
  const OusterMetadata m = RealMetadata("crc_test.json");
  StatusOr<OusterMetadata> back = ParseOusterMetadata(OusterMetadataJson(m), "written");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->beam_altitude_deg, m.beam_altitude_deg);
  EXPECT_EQ(back->beam_azimuth_deg, m.beam_azimuth_deg);
  EXPECT_EQ(back->lidar_mode, m.lidar_mode);
  EXPECT_EQ(back->lidar_profile, m.lidar_profile);
  EXPECT_TRUE(back->sensor_T_imu.isApprox(m.sensor_T_imu, 1e-15));
  EXPECT_TRUE(back->sensor_T_lidar.isApprox(m.sensor_T_lidar, 1e-15));
}

TEST(OusterMetadataTest, BadMetadataNamesTheProblem) {
  const std::string text = ReadText(std::string(RVLIO_TEST_DATA) + "/ouster/OS-1-128_v2.3.0_1024x10.json");
  auto fails = [](const std::string& json, const std::string& what) {
    StatusOr<OusterMetadata> m = ParseOusterMetadata(json, "m.json");
    ASSERT_FALSE(m.ok());
    EXPECT_NE(m.status().message().find(what), std::string::npos) << m.status().message();
    EXPECT_NE(m.status().message().find("m.json"), std::string::npos);
  };
  fails("{", "not a JSON object");
  fails("{}", "lidar_mode");
  std::string mode = text;
  mode.replace(mode.find("\"1024x10\""), 9, "\"fast\"");
  fails(mode, "COLUMNSxRATE");
  std::string profile = text;
  profile.replace(profile.find("RNG15_RFL8_NIR8"), 15, "RNG99_XYZ");
  fails(profile, "udp_profile_lidar");
  std::string imu_profile = text;
  imu_profile.replace(imu_profile.find("\"LEGACY\""), 8, "\"ACCEL99\"");
  fails(imu_profile, "udp_profile_imu");
  std::string beams = text;
  beams.replace(beams.find("\"pixels_per_column\": 128"), 24, "\"pixels_per_column\": 64");
  fails(beams, "pixels_per_column");
}

TEST(OusterPacketTest, EveryProfileRoundTrips) {
  const OusterMetadata base = RealMetadata("OS-1-128_v2.3.0_1024x10.json");
  for (OusterLidarProfile profile :
       {OusterLidarProfile::kLegacy, OusterLidarProfile::kRng19Rfl8Sig16Nir16,
        OusterLidarProfile::kRng15Rfl8Nir8, OusterLidarProfile::kRng19Rfl8Sig16Nir16Dual,
        OusterLidarProfile::kRng15Rfl8Nir8Dual, OusterLidarProfile::kFusaRng15Rfl8Nir8Dual}) {
    SCOPED_TRACE(OusterLidarProfileName(profile));
    const OusterMetadata m = WithProfile(base, profile);
    const OusterLidarPacket in = MakePacket(m, 1795, 3, 1000000000);
    const std::vector<uint8_t> bytes = EncodeOusterLidarPacket(m, in);
    EXPECT_EQ(static_cast<int>(bytes.size()), OusterFormatOf(m).PacketBytes());
    StatusOr<OusterLidarPacket> out = DecodeOusterLidarPacket(m, bytes.data(), bytes.size(), "p");
    ASSERT_TRUE(out.ok()) << out.status().message();
    EXPECT_EQ(out->frame_id, 1795u);
    EXPECT_EQ(out->crc_present, profile != OusterLidarProfile::kLegacy);
    for (size_t c = 0; c < in.columns.size(); ++c) {
      EXPECT_EQ(out->columns[c].t_ns, in.columns[c].t_ns);
      EXPECT_EQ(out->columns[c].measurement_id, in.columns[c].measurement_id);
      EXPECT_EQ(out->columns[c].range_mm, in.columns[c].range_mm);
      EXPECT_TRUE(out->columns[c].valid);
    }
  }
  // The real captures' packet sizes: 8448 (RNG15, 128 beams), 24832 (RNG19),
  // 16640 (FUSA dual), 6464 (legacy, 32 beams).
  EXPECT_EQ(OusterFormatOf(WithProfile(base, OusterLidarProfile::kRng15Rfl8Nir8)).PacketBytes(), 8448);
  EXPECT_EQ(OusterFormatOf(WithProfile(base, OusterLidarProfile::kRng19Rfl8Sig16Nir16)).PacketBytes(), 24832);
  EXPECT_EQ(OusterFormatOf(WithProfile(base, OusterLidarProfile::kFusaRng15Rfl8Nir8Dual)).PacketBytes(), 16640);
}

TEST(OusterPacketTest, WrongSizeOrModeAndBrokenCrc) {
  const OusterMetadata m = RealMetadata("OS-1-128_v2.3.0_1024x10.json");
  std::vector<uint8_t> bytes = EncodeOusterLidarPacket(m, MakePacket(m, 7, 0, 0));
  StatusOr<OusterLidarPacket> cut = DecodeOusterLidarPacket(m, bytes.data(), bytes.size() - 100, "cut");
  ASSERT_FALSE(cut.ok());
  EXPECT_NE(cut.status().message().find("8348 bytes"), std::string::npos) << cut.status().message();
  OusterMetadata half = m;  // 512x10: measurement ids of 1024 columns are outside
  half.lidar_mode = "512x10";
  half.columns_per_frame = 512;
  const std::vector<uint8_t> late = EncodeOusterLidarPacket(m, MakePacket(m, 7, 40, 0));
  StatusOr<OusterLidarPacket> mode = DecodeOusterLidarPacket(half, late.data(), late.size(), "mode");
  ASSERT_FALSE(mode.ok());
  EXPECT_NE(mode.status().message().find("another mode"), std::string::npos);
  bytes[100] ^= 1;
  StatusOr<OusterLidarPacket> flipped = DecodeOusterLidarPacket(m, bytes.data(), bytes.size(), "crc");
  ASSERT_TRUE(flipped.ok());
  EXPECT_FALSE(flipped->crc_present);
}

TEST(OusterPacketTest, ImuPacketUnits) {
  OusterImuPacket p;
  p.sys_t_ns = 10;
  p.accel_t_ns = 20;
  p.gyro_t_ns = 30;
  p.accel_g = Eigen::Vector3f(0.0f, 0.0f, 1.0f);
  p.gyro_deg_s = Eigen::Vector3f(180.0f, 0.0f, -90.0f);
  const std::vector<uint8_t> bytes = EncodeOusterImuPacket(p);
  ASSERT_EQ(bytes.size(), 48u);
  StatusOr<OusterImuPacket> back = DecodeOusterImuPacket(bytes.data(), bytes.size(), "imu");
  ASSERT_TRUE(back.ok());
  const ImuSample s = OusterImuToSample(*back);
  EXPECT_EQ(s.t_ns, 30);
  EXPECT_DOUBLE_EQ(s.acc_imu.z(), 9.80665);
  EXPECT_DOUBLE_EQ(s.gyro_imu.x(), M_PI);
  EXPECT_DOUBLE_EQ(s.gyro_imu.z(), -M_PI / 2);
  EXPECT_FALSE(DecodeOusterImuPacket(bytes.data(), 47, "imu").ok());
}

TEST(OusterPacketTest, Accel32ImuPacketRoundTripsWithItsCrc) {
  OusterMetadata meta;
  meta.imu_profile = "ACCEL32_GYRO32_NMEA";
  meta.imu_measurements_per_packet = 3;
  ASSERT_EQ(OusterImuPacketBytes(meta), 32 + 100 + 3 * 36 + 32);
  std::vector<ImuSample> in(3);
  for (int i = 0; i < 3; ++i) {
    in[i].t_ns = 1000 + 1562500 * i;
    in[i].acc_imu = Eigen::Vector3d(0.25 * i, -0.5, 9.75);
    in[i].gyro_imu = Eigen::Vector3d(0.125, -0.0625 * i, 0.5);
  }
  std::vector<uint8_t> bytes = EncodeOusterAccel32ImuPacket(meta, in);
  bool crc_ok = false;
  StatusOr<std::vector<ImuSample>> out = DecodeOusterImuSamples(meta, bytes.data(), bytes.size(), "imu", &crc_ok);
  ASSERT_TRUE(out.ok()) << out.status().message();
  EXPECT_TRUE(crc_ok);
  ASSERT_EQ(out->size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ((*out)[i].t_ns, in[i].t_ns);
    EXPECT_EQ((*out)[i].acc_imu, in[i].acc_imu);  // SI in the packet: no unit conversion
    EXPECT_EQ((*out)[i].gyro_imu, in[i].gyro_imu);
  }
  bytes[140] ^= 0x01;
  ASSERT_TRUE(DecodeOusterImuSamples(meta, bytes.data(), bytes.size(), "imu", &crc_ok).ok());
  EXPECT_FALSE(crc_ok);
  StatusOr<std::vector<ImuSample>> short_packet =
      DecodeOusterImuSamples(meta, bytes.data(), bytes.size() - 36, "imu.pcap", &crc_ok);
  ASSERT_FALSE(short_packet.ok());
  EXPECT_NE(short_packet.status().message().find("ACCEL32_GYRO32_NMEA"), std::string::npos);
  EXPECT_NE(short_packet.status().message().find("imu.pcap"), std::string::npos);
}

TEST(OusterBeamModelTest, RangeToInvertsThePointFormula) {
  const OusterMetadata m = RealMetadata("OS-1-128_v2.3.0_1024x10.json");
  const OusterBeamModel beams(m);
  for (int mid : {0, 100, 511, 1023}) {
    for (int b : {0, 64, 127}) {
      const Eigen::Vector3d p = beams.PointInSensor(12.345, mid, b);
      EXPECT_NEAR(beams.RangeTo(p, mid, b), 12.345, 1e-9);
    }
  }
  // Column 0 looks along the lidar +x axis: the sensor's -x (rotated 180 deg
  // about z); a level beam 10 m out lies about 10 m behind the sensor origin.
  OusterMetadata level = m;
  std::fill(level.beam_altitude_deg.begin(), level.beam_altitude_deg.end(), 0.0);
  std::fill(level.beam_azimuth_deg.begin(), level.beam_azimuth_deg.end(), 0.0);
  const Eigen::Vector3d p = OusterBeamModel(level).PointInSensor(10.0, 0, 0);
  EXPECT_NEAR(p.x(), -10.0, 1e-9);
  EXPECT_NEAR(p.y(), 0.0, 1e-9);
  EXPECT_NEAR(p.z(), 0.03618, 1e-9);
  // A quarter turn later (mid = W/4): encoder angle 270 deg, lidar -y = sensor +y.
  const Eigen::Vector3d q = OusterBeamModel(level).PointInSensor(10.0, 256, 0);
  EXPECT_NEAR(q.y(), 10.0, 1e-9);
}

// Frames assembled by measurement id: a lost packet leaves its 16 columns
// out (counted), the others keep their times; a late packet is dropped.
TEST(OusterAssemblerTest, LostAndLatePackets) {
  const OusterMetadata m = RealMetadata("OS-1-128_v2.3.0_1024x10.json");
  LidarOptions lidar;
  lidar.min_range = 0.0;
  OusterScanAssembler assembler(m, lidar);
  Scan scan;
  DecodeStats decode;
  const int packets = m.columns_per_frame / m.columns_per_packet;
  int scans = 0;
  for (uint32_t frame : {10u, 11u}) {
    for (int k = 0; k < packets; ++k) {
      if (frame == 10 && k == 5) continue;  // lost
      if (assembler.Add(MakePacket(m, frame, k, frame * 100000000LL), &scan, &decode)) {
        ++scans;
        // Delivered at the window's last column, not a packet later.
        EXPECT_EQ(k, packets - 1);
        if (frame != 10) continue;
        // Frame 10 without packet 5: its columns 80..95 have no point, the
        // rest keep their measurement id's time.
        std::vector<bool> seen(m.columns_per_frame, false);
        for (const LidarPoint& p : scan.points) {
          const int mid = static_cast<int>((p.t_ns - 10 * 100000000LL) / 97656);
          ASSERT_GE(mid, 0);
          ASSERT_LT(mid, m.columns_per_frame);
          seen[mid] = true;
        }
        for (int mid = 0; mid < m.columns_per_frame; ++mid) EXPECT_EQ(seen[mid], mid < 80 || mid >= 96) << mid;
      }
    }
  }
  EXPECT_EQ(scans, 2);
  EXPECT_FALSE(assembler.Add(MakePacket(m, 10, 5, 0), &scan, &decode));  // late: dropped
  EXPECT_FALSE(assembler.Add(MakePacket(m, 11, 5, 0), &scan, &decode));  // its frame is out
  EXPECT_EQ(assembler.stats().late_packets, 2);
  EXPECT_FALSE(assembler.Flush(&scan, &decode));  // nothing pending
  // A frame that loses its end is delivered when the next frame begins.
  for (int k = 0; k < packets - 1; ++k) EXPECT_FALSE(assembler.Add(MakePacket(m, 12, k, 0), &scan, &decode));
  EXPECT_TRUE(assembler.Add(MakePacket(m, 13, 0, 0), &scan, &decode));
  EXPECT_TRUE(assembler.Flush(&scan, &decode));  // frame 13's first packet
  EXPECT_EQ(assembler.stats().frames, 4);
  EXPECT_EQ(assembler.stats().missing_columns, 16 + 16 + (m.columns_per_frame - 16));
  EXPECT_EQ(assembler.stats().incomplete_frames, 3);
  // 16-bit frame ids wrap: 65535 -> 0 is a later frame.
  EXPECT_TRUE(OusterFrameAfter(65535, 0, false));
  EXPECT_FALSE(OusterFrameAfter(0, 65535, false));
}

// A column window that wraps past column 0 ([1000, 100] of 1024): the
// sensor sends columns 1000..1023 of frame f, then 0..100 of frame f + 1;
// one scan holds both arcs, columns 1000..1023 then 0..100, times increasing.
TEST(OusterAssemblerTest, WindowWrappingPastColumnZero) {
  OusterMetadata m = RealMetadata("OS-1-128_v2.3.0_1024x10.json");
  m.column_first = 1000;
  m.column_last = 100;
  ASSERT_EQ(m.WindowColumns(), 24 + 101);
  LidarOptions lidar;
  lidar.min_range = 0.0;
  OusterScanAssembler assembler(m, lidar);
  Scan scan;
  DecodeStats decode;
  std::vector<Scan> scans;
  // The packets a windowed sensor sends (those holding window columns), for
  // frames 65534..65537 (16-bit frame ids wrap at 65536).
  for (uint32_t frame = 65534; frame < 65538; ++frame) {
    for (int k : {0, 1, 2, 3, 4, 5, 6, 62, 63}) {
      const TimeNs t0_ns = static_cast<TimeNs>(frame) * 100000000LL;
      if (assembler.Add(MakePacket(m, frame & 0xFFFFu, k, t0_ns), &scan, &decode)) scans.push_back(scan);
    }
  }
  if (assembler.Flush(&scan, &decode)) scans.push_back(scan);
  // Windows: (head of 65534 alone), 65534 tail + 65535 head, 65535 + 0, 0 + 1,
  // (tail of frame 1 alone).
  ASSERT_EQ(scans.size(), 5u);
  EXPECT_EQ(assembler.stats().frames, 5);
  EXPECT_EQ(assembler.stats().incomplete_frames, 2);
  EXPECT_EQ(assembler.stats().missing_columns, 24 + 101);
  EXPECT_EQ(assembler.stats().late_packets, 0);
  for (size_t i = 1; i + 1 < scans.size(); ++i) {
    const Scan& s = scans[i];
    ASSERT_FALSE(s.points.empty());
    const TimeNs tail_frame_ns = static_cast<TimeNs>(65533 + i) * 100000000LL;
    std::vector<int> columns;  // in point order
    for (size_t j = 0; j < s.points.size(); ++j) {
      if (j > 0) {
        ASSERT_GE(s.points[j].t_ns, s.points[j - 1].t_ns);
      }
      const TimeNs dt = s.points[j].t_ns - tail_frame_ns;
      const int mid = dt >= 100000000LL ? static_cast<int>((dt - 100000000LL) / 97656) : static_cast<int>(dt / 97656);
      if (columns.empty() || columns.back() != mid) columns.push_back(mid);
    }
    ASSERT_EQ(columns.size(), 125u);
    EXPECT_EQ(columns.front(), 1000);
    EXPECT_EQ(columns[23], 1023);
    EXPECT_EQ(columns[24], 0);
    EXPECT_EQ(columns.back(), 100);
    EXPECT_EQ(s.t_start_ns, tail_frame_ns + 1000 * 97656);
  }
}

TEST(PcapTest, FragmentedDatagramsRoundTrip) {
  const fs::path dir = fs::temp_directory_path() / ("rvlio_pcap_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "x.pcap").string();
  std::vector<UdpDatagram> in;
  for (int i = 0; i < 5; ++i) {
    UdpDatagram d;
    d.t_ns = 1700000000123456789LL + i * 1000;
    d.src_port = 7502;
    d.dst_port = static_cast<uint16_t>(i == 2 ? 7503 : 7502);
    d.payload.resize(i == 2 ? 48 : 24832);
    for (size_t k = 0; k < d.payload.size(); ++k) d.payload[k] = static_cast<uint8_t>(k * 7 + i);
    in.push_back(d);
  }
  PcapWriter writer;
  ASSERT_TRUE(writer.Open(path).ok());
  for (const UdpDatagram& d : in) ASSERT_TRUE(writer.Write(d).ok());
  ASSERT_TRUE(writer.Close().ok());
  StatusOr<PcapReader> reader = PcapReader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  UdpDatagram d;
  for (const UdpDatagram& want : in) {
    StatusOr<bool> got = reader->Next(&d);
    ASSERT_TRUE(got.ok() && *got);
    EXPECT_EQ(d.t_ns, want.t_ns);
    EXPECT_EQ(d.dst_port, want.dst_port);
    EXPECT_EQ(d.payload, want.payload);
  }
  StatusOr<bool> end = reader->Next(&d);
  ASSERT_TRUE(end.ok());
  EXPECT_FALSE(*end);
  EXPECT_GT(reader->stats().fragments, 60);  // 24840 bytes of UDP in 1480-byte fragments
  EXPECT_EQ(reader->stats().incomplete_datagrams, 0);
  // Cut inside the last record: the reader says so.
  fs::resize_file(path, fs::file_size(path) - 10);
  StatusOr<PcapReader> cut = PcapReader::Open(path);
  ASSERT_TRUE(cut.ok());
  Status error;
  while (true) {
    StatusOr<bool> got = cut->Next(&d);
    if (!got.ok()) {
      error = got.status();
      break;
    }
    ASSERT_TRUE(*got) << "the cut record was not reported";
  }
  EXPECT_NE(error.message().find("truncated"), std::string::npos) << error.message();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rvlio

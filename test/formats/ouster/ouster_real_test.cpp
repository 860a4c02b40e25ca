// Ouster packet recordings that real sensors wrote (test/data/ouster: the
// Ouster SDK's test captures and ROS1 packet bag, README.md there): every
// capture decodes, frames / columns / IMU packets match what the files hold,
// and the decoded geometry and IMU are physically plausible.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/constraints/plane_fit.h"
#include "rvlio/formats/ouster.h"
#include "ouster_test_util.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio {
namespace {

std::string RealCapture(const std::string& name) { return std::string(RVLIO_TEST_DATA) + "/ouster/" + name; }

using testing_ouster::Decoded;

// Every return (no range crop), every IMU sample.
LidarOptions AllReturns() {
  LidarOptions lidar;
  lidar.min_range = 0.0;
  lidar.max_range = 1e6;
  return lidar;
}

Decoded ReadAll(const std::string& path, const LidarOptions& lidar = AllReturns()) {
  return testing_ouster::ReadAll(path, lidar, ImuOptions());
}

// Distinct column times of a scan (one per column with a return).
std::vector<TimeNs> ColumnTimes(const Scan& scan) {
  std::vector<TimeNs> t;
  for (const LidarPoint& p : scan.points) t.push_back(p.t_ns);
  std::sort(t.begin(), t.end());
  t.erase(std::unique(t.begin(), t.end()), t.end());
  return t;
}

struct Expected {
  const char* pcap;
  const char* json;
  const char* profile;
  int frames;
  int imu;
  int incomplete;  // frames with missing columns (the capture starts or ends mid-frame)
};

// Frame and IMU counts: what the files hold (192 lidar packets = 64 per
// frame x 3 for the low-bandwidth capture, README). The FUSA capture holds
// 8 packets (128 of 1024 columns: one incomplete frame); crc_test holds a
// 512-column frame and the first 2 packets of the next (incomplete).
const Expected kCaptures[] = {
    {"OS-1-128_v2.3.0_1024x10_lb_n3.pcap", "OS-1-128_v2.3.0_1024x10.json", "RNG15_RFL8_NIR8", 3, 30, 0},
    {"OS-0-128-U1_v2.3.0_1024x10.pcap", "OS-0-128-U1_v2.3.0_1024x10.json", "RNG15_RFL8_NIR8", 1, 10, 0},
    {"OS-2-128-U1_v2.3.0_1024x10.pcap", "OS-2-128-U1_v2.3.0_1024x10.json", "RNG19_RFL8_SIG16_NIR16", 1, 10, 0},
    {"OS-1-128_767798045_1024x10_20230712_120049.pcap", "OS-1-128_767798045_1024x10_20230712_120049.json",
     "FUSA_RNG15_RFL8_NIR8_DUAL", 1, 2, 1},
    {"crc_test.pcap", "crc_test.json", "RNG15_RFL8_NIR8", 2, 10, 1},
    {"windowed_frame1.pcap", "windowed_frame1_0.json", "RNG15_RFL8_NIR8", 1, 10, 0},
    {"OS-1-32-G_v2.1.1_1024x10.pcap", "OS-1-32-G_v2.1.1_1024x10.json", "LEGACY", 1, 0, 0},
};

TEST(OusterRealTest, EveryCaptureDecodesWithItsMetadata) {
  for (const Expected& e : kCaptures) {
    SCOPED_TRACE(e.pcap);
    StatusOr<BagInfo> info = ReadBagInfo(RealCapture(e.pcap), "", RealCapture(e.json));
    ASSERT_TRUE(info.ok()) << info.status().message();
    ASSERT_TRUE(info->ouster.has_value());
    EXPECT_EQ(info->ouster->lidar_profile, e.profile);
    EXPECT_EQ(info->ouster->imu_packets, e.imu);
    EXPECT_EQ(info->ouster->frames, e.frames);
    EXPECT_EQ(info->ouster->incomplete_frames, e.incomplete);
    EXPECT_EQ(info->ouster->late_packets, 0);
    EXPECT_EQ(info->ouster->crc_errors, 0);
    EXPECT_EQ(info->ouster->crc, std::string(e.pcap) == "crc_test.pcap");  // the one with a CRC-64
    // Every lidar packet's columns land in a frame: frames x window columns
    // = packets x 16 columns - missing, up to the columns outside the window.
    const int64_t sent = info->ouster->lidar_packets * 16;
    const int64_t placed = info->ouster->frames * info->ouster->window_columns - info->ouster->missing_columns;
    EXPECT_LE(placed, sent);
    EXPECT_GE(placed, sent - 16 * 2);  // a windowed capture sends its edge packets' outside columns
    const Decoded d = ReadAll(RealCapture(e.pcap), [&] {
      LidarOptions l = AllReturns();
      l.ouster_metadata = RealCapture(e.json);
      return l;
    }());
    EXPECT_EQ(static_cast<int>(d.imu.size()), e.imu);
    ASSERT_FALSE(d.scans.empty());
  }
}

TEST(OusterRealTest, MetadataIsFoundNextToTheCapture) {
  // STEM.json, STEM_0.json, and the longest NAME.json with STEM = NAME_...
  for (const char* pcap : {"crc_test.pcap", "windowed_frame1.pcap", "OS-1-128_v2.3.0_1024x10_lb_n3.pcap"}) {
    StatusOr<BagInfo> info = ReadBagInfo(RealCapture(pcap));
    ASSERT_TRUE(info.ok()) << pcap << ": " << info.status().message();
    ASSERT_TRUE(info->ouster.has_value());
  }
  StatusOr<BagInfo> lb = ReadBagInfo(RealCapture("OS-1-128_v2.3.0_1024x10_lb_n3.pcap"));
  ASSERT_TRUE(lb.ok());
  EXPECT_EQ(lb->ouster->metadata, RealCapture("OS-1-128_v2.3.0_1024x10.json"));
}

TEST(OusterRealTest, LowBandwidthCaptureHasThreeCompleteFrames) {
  StatusOr<BagInfo> info = ReadBagInfo(RealCapture("OS-1-128_v2.3.0_1024x10_lb_n3.pcap"));
  ASSERT_TRUE(info.ok()) << info.status().message();
  const OusterRecordingInfo& o = *info->ouster;
  EXPECT_EQ(o.prod_line, "OS-1-128");
  EXPECT_EQ(o.firmware, "v2.3.0");
  EXPECT_EQ(o.lidar_mode, "1024x10");
  EXPECT_EQ(o.lidar_packets, 192);
  EXPECT_EQ(o.frames, 3);
  EXPECT_EQ(o.missing_columns, 0);
  EXPECT_EQ(o.imu_packets, 30);
  EXPECT_NEAR(o.imu_rate_hz, 100.0, 2.0);
  EXPECT_NEAR(o.frame_rate_hz, 10.0, 0.1);
}

TEST(OusterRealTest, ColumnTimesIncreaseAtTheModeRate) {
  const Decoded d = ReadAll(RealCapture("OS-1-128_v2.3.0_1024x10_lb_n3.pcap"));
  ASSERT_EQ(d.scans.size(), 3u);
  for (const Scan& scan : d.scans) {
    const std::vector<TimeNs> t = ColumnTimes(scan);
    ASSERT_GT(t.size(), 1000u);  // nearly every column has a return
    // 1024 columns at 10 Hz: 97.66 us apart; a column without any return
    // leaves a double gap.
    for (size_t i = 1; i < t.size(); ++i) {
      const double dt_us = (t[i] - t[i - 1]) * 1e-3;
      EXPECT_GT(dt_us, 60.0);
      EXPECT_LT(dt_us, 400.0);
    }
    EXPECT_NEAR((scan.t_end_ns - scan.t_start_ns) * 1e-9, 0.1, 0.002);
  }
}

// The points 2-12 m out on the 16 lowest beams lie on one plane below the
// sensor (the ground), level in the sensor frame: a wrong sign of the beam
// altitudes or a wrong lidar_to_sensor_transform would put them elsewhere.
// The accelerometer's mean direction is printed, not asserted: on this
// capture it is about 23 deg from the ground normal (the rig stands on a
// slope or accelerates), so the ground cannot check the IMU axes here.
TEST(OusterRealTest, GroundPlaneBelowTheSensor) {
  const Decoded d = ReadAll(RealCapture("OS-1-128_v2.3.0_1024x10_lb_n3.pcap"));
  ASSERT_EQ(d.scans.size(), 3u);
  std::vector<Eigen::Vector3d> ground;
  for (const LidarPoint& p : d.scans[0].points) {
    const double horizontal = p.p_lidar.head<2>().norm();
    if (p.ring >= 112 && horizontal > 2.0 && horizontal < 12.0) ground.push_back(p.p_lidar.cast<double>());
  }
  ASSERT_GT(ground.size(), 2000u);
  PlaneThresholds loose;
  loose.max_plane_distance = 1e9;
  const LocalPlane plane = FitLocalPlane(ground, loose);
  // Refit on the points within 10 cm of the first fit.
  std::vector<Eigen::Vector3d> inliers;
  for (const Eigen::Vector3d& p : ground)
    if (std::abs(plane.normal.dot(p - plane.centroid)) < 0.10) inliers.push_back(p);
  ASSERT_GT(inliers.size(), ground.size() / 2);
  const LocalPlane refit = FitLocalPlane(inliers, loose);
  double rms = 0.0;
  for (const Eigen::Vector3d& p : inliers) rms += std::pow(refit.normal.dot(p - refit.centroid), 2);
  rms = std::sqrt(rms / inliers.size());
  EXPECT_LT(rms, 0.05);
  const double tilt_deg = std::acos(std::min(1.0, std::abs(refit.normal.z()))) * 180.0 / M_PI;
  EXPECT_LT(tilt_deg, 5.0) << refit.normal.transpose();
  EXPECT_LT(refit.centroid.z(), -1.0);  // the ground below the sensor
  Eigen::Vector3d acc = Eigen::Vector3d::Zero();
  for (const ImuSample& s : d.imu) acc += s.acc_imu;
  const double acc_deg = std::acos(std::min(1.0, std::abs(acc.normalized().dot(refit.normal)))) * 180.0 / M_PI;
  std::printf("ground: %zu of %zu points, rms %.4f m, tilt %.2f deg, %.2f m below; mean acceleration "
              "%.2f deg from its normal\n",
              inliers.size(), ground.size(), rms, tilt_deg, -refit.centroid.z(), acc_deg);
}

TEST(OusterRealTest, RangesWithinTheSensorsLimits) {
  const Decoded d = ReadAll(RealCapture("OS-1-128_v2.3.0_1024x10_lb_n3.pcap"));
  ASSERT_EQ(d.scans.size(), 3u);
  for (const Scan& scan : d.scans) {
    ASSERT_GT(scan.points.size(), 50000u);
    for (const LidarPoint& p : scan.points) {
      // OS-1: 0.3 m minimum (inside the window: the lidar origin is 36 mm
      // above the sensor origin), 120 m rated, the low-bandwidth profile's
      // range field ends at 262 m.
      ASSERT_LT(p.p_lidar.norm(), 262.2f);
      ASSERT_GT(p.p_lidar.norm(), 0.0f);
    }
  }
}

TEST(OusterRealTest, ImuIsGravityAndASlowTurn) {
  const Decoded d = ReadAll(RealCapture("OS-1-128_v2.3.0_1024x10_lb_n3.pcap"));
  ASSERT_EQ(d.imu.size(), 30u);
  double acc = 0.0, gyro_max_deg = 0.0;
  for (const ImuSample& s : d.imu) {
    acc += s.acc_imu.norm();
    gyro_max_deg = std::max(gyro_max_deg, s.gyro_imu.norm() * 180.0 / M_PI);
  }
  acc /= d.imu.size();
  EXPECT_NEAR(acc, 9.81, 0.15 * 9.81);
  EXPECT_LT(gyro_max_deg, 10.0);  // a few degrees per second (README: up to about 4.5)
  EXPECT_GT(gyro_max_deg, 0.5);   // and not all zero
  for (size_t i = 1; i < d.imu.size(); ++i) EXPECT_NEAR((d.imu[i].t_ns - d.imu[i - 1].t_ns) * 1e-6, 10.0, 1.0);
}

// Firmware 3.2, IMU profile ACCEL32_GYRO32_NMEA, no lidar packets: 8 IMU
// packets of 8 measurements (imu_data_format) = 64 samples at 640 Hz of a
// sensor at rest. The packet holds SI units: every accelerometer value is a
// whole number of the +-16 g range's step (16 g / 2^15, g = 9.80665 m/s^2,
// accel_fsr EXTENDED) and every gyroscope value a whole number of the
// +-2000 deg/s range's step in rad/s: the units decoding assumes.
TEST(OusterRealTest, ImuOnlyCaptureOfFirmware32) {
  const Decoded d = ReadAll(RealCapture("imu_zm_no_lidar.pcap"));
  EXPECT_TRUE(d.scans.empty());
  ASSERT_EQ(d.imu.size(), 64u);
  EXPECT_NE(std::find_if(d.warnings.begin(), d.warnings.end(),
                         [](const std::string& w) { return w.find("no lidar packets") != std::string::npos; }),
            d.warnings.end());
  const double accel_step = 16.0 / 32768.0 * 9.80665;
  const double gyro_step = 2000.0 / 32768.0 * M_PI / 180.0;
  double acc = 0.0;
  for (const ImuSample& s : d.imu) {
    acc += s.acc_imu.norm();
    EXPECT_LT(s.gyro_imu.norm() * 180.0 / M_PI, 5.0);  // at rest
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(s.acc_imu[i] / accel_step, std::round(s.acc_imu[i] / accel_step), 0.01);
      EXPECT_NEAR(s.gyro_imu[i] / gyro_step, std::round(s.gyro_imu[i] / gyro_step), 0.05);
    }
  }
  double gyro_max_deg = 0.0;
  for (const ImuSample& s : d.imu) gyro_max_deg = std::max(gyro_max_deg, s.gyro_imu.norm() * 180.0 / M_PI);
  std::printf("imu_zm_no_lidar: %zu samples, mean |a| %.3f m/s^2, max |w| %.2f deg/s, %.1f Hz\n", d.imu.size(),
              acc / d.imu.size(), gyro_max_deg,
              (d.imu.size() - 1) / ((d.imu.back().t_ns - d.imu.front().t_ns) * 1e-9));
  EXPECT_NEAR(acc / d.imu.size(), 9.81, 0.15 * 9.81);
  for (size_t i = 1; i < d.imu.size(); ++i)
    EXPECT_NEAR((d.imu[i].t_ns - d.imu[i - 1].t_ns) * 1e-6, 1.5625, 0.05);  // 640 Hz, increasing
  StatusOr<BagInfo> info = ReadBagInfo(RealCapture("imu_zm_no_lidar.pcap"));
  ASSERT_TRUE(info.ok()) << info.status().message();
  ASSERT_TRUE(info->ouster.has_value());
  EXPECT_EQ(info->ouster->lidar_packets, 0);
  EXPECT_EQ(info->ouster->imu_packets, 8);
  EXPECT_EQ(info->ouster->lidar_source, "none");
}

TEST(OusterRealTest, Ros1PacketBagDecodesToOneFrameOf512Columns) {
  StatusOr<BagInfo> info = ReadBagInfo(RealCapture("512x10_raw.bag"));
  ASSERT_TRUE(info.ok()) << info.status().message();
  ASSERT_TRUE(info->ouster.has_value());
  EXPECT_EQ(info->ouster->metadata, "topic /os_node0/metadata");
  EXPECT_EQ(info->ouster->lidar_mode, "512x10");
  EXPECT_EQ(info->ouster->lidar_packets, 32);
  EXPECT_EQ(info->ouster->imu_packets, 10);
  EXPECT_EQ(info->ouster->frames, 1);
  EXPECT_EQ(info->ouster->missing_columns, 0);
  const Decoded d = ReadAll(RealCapture("512x10_raw.bag"));
  ASSERT_EQ(d.scans.size(), 1u);
  EXPECT_EQ(ColumnTimes(d.scans[0]).size() <= 512u, true);
  EXPECT_GT(ColumnTimes(d.scans[0]).size(), 450u);
  EXPECT_EQ(d.imu.size(), 10u);
}

}  // namespace
}  // namespace rvlio

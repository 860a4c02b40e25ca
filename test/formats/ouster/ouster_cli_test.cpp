// `rvlio info` and `rvlio run` on Ouster captures, and the bad inputs of a
// packet recording: each is exit 2 with one line naming the problem.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_util.h"
#include "rvlio/formats/pcap.h"
#include "rvlio/formats/trajectory_io.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;
using testing_cli::MakeTempDir;
using testing_cli::RunTool;
using testing_cli::ToolRun;

std::string Data(const std::string& name) { return std::string(RVLIO_TEST_DATA) + "/ouster/" + name; }
const std::string kLb = "OS-1-128_v2.3.0_1024x10_lb_n3.pcap";

int Lines(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

void ExpectOneLineExit2(const ToolRun& r, const std::string& what) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
}

// A copy of a real capture with each datagram changed by `edit` (false drops it).
template <class Edit>
void Rewrite(const std::string& from, const std::string& to, Edit edit) {
  StatusOr<PcapReader> in = PcapReader::Open(from);
  ASSERT_TRUE(in.ok());
  PcapWriter out;
  ASSERT_TRUE(out.Open(to).ok());
  UdpDatagram d;
  int index = 0;
  while (true) {
    StatusOr<bool> got = in->Next(&d);
    ASSERT_TRUE(got.ok());
    if (!*got) break;
    if (edit(index++, &d)) {
      ASSERT_TRUE(out.Write(d).ok());
    }
  }
  ASSERT_TRUE(out.Close().ok());
}

class OusterCliTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = MakeTempDir("rvlio_ouster_cli"); }
  void TearDown() override { fs::remove_all(dir_); }
  std::string dir_;
};

TEST_F(OusterCliTest, InfoReportsTheSensor) {
  const ToolRun r = RunTool("info --bag " + Data(kLb), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* want : {"storage:  pcap", "OS-1-128, firmware v2.3.0", "1024x10 (128 beams",
                           "RNG15_RFL8_NIR8", "192 packets", "frames:   3 (", "0 incomplete",
                           "30 packets, 100.", "0 late packets"})
    EXPECT_NE(r.out.find(want), std::string::npos) << want << "\n" << r.out;
}

// Firmware 3.2 capture with IMU packets only (lidar profile
// RNG19_RFL8_SIG16_NIR16_ZONE16, not decoded): info reports the IMU and says
// there are no lidar packets; lidar packets under that profile are refused.
TEST_F(OusterCliTest, ImuOnlyCaptureAndUndecodedLidarProfile) {
  const ToolRun r = RunTool("info --bag " + Data("imu_zm_no_lidar.pcap"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* want : {"RNG19_RFL8_SIG16_NIR16_ZONE16 (not decoded)", "IMU ACCEL32_GYRO32_NMEA",
                           "no lidar packets: IMU samples only", "8 packets, 639.", "0 IMU CRC errors"})
    EXPECT_NE(r.out.find(want), std::string::npos) << want << "\n" << r.out;
  std::string json = testing_cli::ReadFile(Data("OS-2-128-U1_v2.3.0_1024x10.json"));
  const std::string profile = "\"RNG19_RFL8_SIG16_NIR16\"";
  for (size_t at = json.find(profile); at != std::string::npos; at = json.find(profile, at + 1))
    json.replace(at, profile.size(), "\"RNG19_RFL8_SIG16_NIR16_ZONE16\"");
  std::ofstream(dir_ + "/zone.json") << json;
  ExpectOneLineExit2(RunTool("info --bag " + Data("OS-2-128-U1_v2.3.0_1024x10.pcap") + " --ouster-metadata " +
                                 dir_ + "/zone.json",
                             dir_),
                     "lidar packets of profile RNG19_RFL8_SIG16_NIR16_ZONE16");
}

// A column window outside the mode's columns (600 of a 512-column mode).
TEST_F(OusterCliTest, ColumnWindowOutsideTheMode) {
  std::string json = testing_cli::ReadFile(Data("windowed_frame1_0.json"));
  const size_t at = json.find("256", json.find("\"column_window\""));
  ASSERT_NE(at, std::string::npos);
  json.replace(at, 3, "600");
  std::ofstream(dir_ + "/window.json") << json;
  ExpectOneLineExit2(RunTool("info --bag " + Data("windowed_frame1.pcap") + " --ouster-metadata " + dir_ +
                                 "/window.json",
                             dir_),
                     "column_window");
}

TEST_F(OusterCliTest, CaptureWithoutMetadata) {
  fs::copy_file(Data(kLb), dir_ + "/alone.pcap");
  ExpectOneLineExit2(RunTool("info --bag " + dir_ + "/alone.pcap", dir_), "--ouster-metadata");
  ExpectOneLineExit2(RunTool("run --bag " + dir_ + "/alone.pcap --out " + dir_ + "/out", dir_),
                     "no Ouster metadata");
  EXPECT_FALSE(fs::exists(dir_ + "/out/trajectory.tum"));
  // The OS-1-64 firmware 2.0 capture comes without its JSON.
  ExpectOneLineExit2(RunTool("info --bag " + Data("OS-1-64_1024x10_fw20.pcap"), dir_), "no Ouster metadata");
}

TEST_F(OusterCliTest, MetadataOfAnotherProfileOrSensor) {
  ExpectOneLineExit2(
      RunTool("info --bag " + Data(kLb) + " --ouster-metadata " + Data("OS-2-128-U1_v2.3.0_1024x10.json"), dir_),
      "lidar packet of 8448 bytes");
  ExpectOneLineExit2(RunTool("run --bag " + Data(kLb) + " --ouster-metadata " + Data("crc_test.json") +
                                 " --out " + dir_ + "/out",
                             dir_),
                     "another sensor");
  ExpectOneLineExit2(RunTool("info --bag " + Data(kLb) + " --ouster-metadata " + dir_ + "/none.json", dir_),
                     "cannot read Ouster metadata");
}

TEST_F(OusterCliTest, TruncatedPackets) {
  // A lidar datagram cut short (a capture with a small snap length looks so).
  Rewrite(Data(kLb), dir_ + "/short.pcap", [](int index, UdpDatagram* d) {
    if (index == 40 && d->payload.size() > 1000) d->payload.resize(d->payload.size() - 100);
    return true;
  });
  fs::copy_file(Data("OS-1-128_v2.3.0_1024x10.json"), dir_ + "/short.json");
  ExpectOneLineExit2(RunTool("info --bag " + dir_ + "/short.pcap", dir_), "lidar packet of 8348 bytes");
  // The file cut inside a record.
  fs::copy_file(Data(kLb), dir_ + "/cut.pcap");
  fs::resize_file(dir_ + "/cut.pcap", fs::file_size(dir_ + "/cut.pcap") / 2);
  fs::copy_file(Data("OS-1-128_v2.3.0_1024x10.json"), dir_ + "/cut.json");
  ExpectOneLineExit2(RunTool("info --bag " + dir_ + "/cut.pcap", dir_), "truncated");
}

TEST_F(OusterCliTest, TwoSensorsOnDifferentPorts) {
  Rewrite(Data(kLb), dir_ + "/two.pcap", [](int index, UdpDatagram* d) {
    if (d->payload.size() > 1000 && index % 2 == 1) d->dst_port = 7504;
    return true;
  });
  fs::copy_file(Data("OS-1-128_v2.3.0_1024x10.json"), dir_ + "/two.json");
  ExpectOneLineExit2(RunTool("info --bag " + dir_ + "/two.pcap", dir_), "two sensors");
  ExpectOneLineExit2(RunTool("run --bag " + dir_ + "/two.pcap --out " + dir_ + "/out", dir_), "port 7504");
}

// The three frames through `rvlio run` (IESKF with the capture's IMU; the
// extrinsic from the metadata). What this shows: real packets decode into
// scans the estimator registers, with a relative motion close to what the
// SDK's own tools computed (a peer's estimate, hence 5 cm). What it does
// not: accuracy (three frames, 0.2 s, no ground truth).
TEST_F(OusterCliTest, RunFollowsTheSdkPoses) {
  const ToolRun r = RunTool("run --bag " + Data(kLb) + " --out " + dir_ + "/out --quiet " +
                                "--set imu.init_duration=0.05",
                            dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("extrinsics.imu_T_lidar from the Ouster metadata"), std::string::npos) << r.err;
  StatusOr<Trajectory> est = ReadTum(dir_ + "/out/trajectory.tum");
  ASSERT_TRUE(est.ok()) << est.status().message();
  std::ifstream kitti(Data("OS-1-128_v2.3.0_1024x10_lb_n3_poses_kitti.txt"));
  std::vector<Eigen::Vector3d> sdk;
  for (double v[12]; kitti >> v[0];) {
    for (int i = 1; i < 12; ++i) kitti >> v[i];
    sdk.emplace_back(v[3], v[7], v[11]);
  }
  ASSERT_EQ(sdk.size(), 3u);
  ASSERT_GE(est->size(), 2u);
  // The estimate's last poses are the capture's last frames.
  const size_t n = std::min<size_t>(est->size(), 3);
  for (size_t k = 1; k < n; ++k) {
    const Trajectory& e = *est;
    const size_t a = e.size() - n + k - 1, b = a + 1;
    const double est_m = (e[b].p_world_imu - e[a].p_world_imu).norm();
    const double sdk_m = (sdk[3 - n + k] - sdk[3 - n + k - 1]).norm();
    std::printf("frame step %zu: rvlio %.4f m, SDK %.4f m\n", k, est_m, sdk_m);
    EXPECT_NEAR(est_m, sdk_m, 0.05);
  }
}

}  // namespace
}  // namespace rvlio

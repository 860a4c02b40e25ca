// End to end: `rvlio info` on a generated bag and on bad input.
#include <stdlib.h>
#include <sys/wait.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

#include "rvlio/formats/sensor_bag.h"

namespace rvlio {
namespace {

struct CmdResult {
  int exit_code = -1;
  std::string out, err;
};

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

class InfoCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = ::testing::TempDir() + "rvlio_info_XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  CmdResult Info(const std::string& args) {
    const std::string out = dir_ + "/stdout", err = dir_ + "/stderr";
    const std::string cmd = std::string(RVLIO_BIN) + " info " + args + " >" + out + " 2>" + err;
    const int status = std::system(cmd.c_str());
    CmdResult r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = Slurp(out);
    r.err = Slurp(err);
    return r;
  }

  // Two 10 Hz sweeps of 4 x 16 points and 200 Hz IMU.
  std::string WriteBag() {
    const std::string path = dir_ + "/sample.bag";
    auto writer = SensorBagWriter::Create(path);
    EXPECT_TRUE(writer.ok());
    const TimeNs t0 = 1600000000 * kNsPerSecond;
    for (int k = 0; k < 2; ++k) {
      Scan s;
      s.t_start_ns = t0 + k * 100000000LL;
      s.t_end_ns = s.t_start_ns + 99000000LL;
      for (int i = 0; i < 64; ++i) {
        LidarPoint p;
        p.p_lidar = Eigen::Vector3f(5.0f * std::cos(0.1f * i), 5.0f * std::sin(0.1f * i), 0.5f);
        p.t_ns = s.t_start_ns + (i % 16) * 6000000LL;
        p.ring = uint16_t(i / 16);
        s.points.push_back(p);
      }
      EXPECT_TRUE((*writer)->WriteOusterScan("/os_cloud_node/points", "os", s, 4, 16).ok());
    }
    for (int i = 0; i < 40; ++i) {
      ImuSample imu;
      imu.t_ns = t0 + i * 5000000LL;
      EXPECT_TRUE((*writer)->WriteImu("/imu/data", "imu", imu).ok());
    }
    EXPECT_TRUE((*writer)->Close().ok());
    return path;
  }
  std::string dir_;
};

TEST_F(InfoCliTest, DescribesAGeneratedBag) {
  const std::string bag = WriteBag();
  CmdResult r = Info("--bag " + bag);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  EXPECT_NE(r.out.find("bag:      " + bag), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("messages: 42"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("duration: 0.199 s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("start:    1600000000.000000000 s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("end:      1600000000.199000000 s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("/imu/data  sensor_msgs/Imu  40 msgs  200.00 Hz"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("/os_cloud_node/points  sensor_msgs/PointCloud2  2 msgs  10.00 Hz"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("layout: ouster (header stamp marks the scan start)"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("fields: x,y,z,intensity,t,reflectivity,ring,ambient,range"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("points per scan: 64.0 (mean of first 2)"), std::string::npos) << r.out;

  CmdResult only = Info("--bag " + bag + " --lidar-topic /os_cloud_node/points");
  EXPECT_EQ(only.exit_code, 0) << only.err;
}

TEST_F(InfoCliTest, BadInputExitsTwoWithOneLine) {
  CmdResult missing = Info("--bag " + dir_ + "/missing.bag");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_EQ(missing.err, "rvlio info: error: bag '" + dir_ + "/missing.bag' does not exist\n");
  EXPECT_TRUE(missing.out.empty());

  std::ofstream(dir_ + "/text.bag") << "not a bag\n";
  CmdResult text = Info("--bag " + dir_ + "/text.bag");
  EXPECT_EQ(text.exit_code, 2);
  EXPECT_EQ(text.err.rfind("rvlio info: error: '" + dir_ + "/text.bag' is not a readable ROS1 bag", 0),
            0u) << text.err;

  const std::string bag = WriteBag();
  CmdResult topic = Info("--bag " + bag + " --lidar-topic /velodyne_points");
  EXPECT_EQ(topic.exit_code, 2);
  EXPECT_NE(topic.err.find("/os_cloud_node/points (sensor_msgs/PointCloud2)"), std::string::npos)
      << topic.err;

  CmdResult no_bag = Info("");
  EXPECT_EQ(no_bag.exit_code, 2);
  EXPECT_NE(no_bag.err.find("--bag"), std::string::npos);
}

}  // namespace
}  // namespace rvlio

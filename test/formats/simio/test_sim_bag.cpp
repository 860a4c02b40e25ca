// A short simulated sequence written as a ROS1 bag: Debian's python3-rosbag
// reads it (message counts, cloud layout), and the library's own reader
// returns exactly the simulated IMU samples and scans.
#include <unistd.h>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "rvlio/config/config.h"
#include "rvlio/formats/sensor_bag.h"
#include "rvlio/odometry/options.h"
#include "rvlio/sim/presets.h"
#include "rvlio/sim/simulator.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
  const fs::path dir = fs::temp_directory_path() / ("rvlio_simio_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

SimOptions ShortTunnel() {
  SimOptions o = *sim::PresetOptions("tunnel");
  o.duration = 2.5;
  o.lidar.columns = 128;
  return o;
}

struct Written {
  std::vector<ImuSample> imu;
  std::vector<Scan> scans;
};

Written WriteSimulatedBag(const SimOptions& o, const std::string& path) {
  Written w;
  auto simulator = sim::Simulator::Create(o);
  EXPECT_TRUE(simulator.ok());
  auto writer = SensorBagWriter::Create(path);
  EXPECT_TRUE(writer.ok()) << writer.status().message();
  Status error;
  (*simulator)
      ->Run(
          [&](const ImuSample& m) {
            w.imu.push_back(m);
            error = (*writer)->WriteImu(o.imu.topic, o.imu.frame_id, m);
            return error.ok();
          },
          [&](const Scan& s, int rows, int cols) {
            w.scans.push_back(s);
            error = (*writer)->WriteOusterScan(o.lidar.topic, o.lidar.frame_id, s, rows, cols);
            return error.ok();
          });
  EXPECT_TRUE(error.ok()) << error.message();
  EXPECT_TRUE((*writer)->Close().ok());
  return w;
}

// Debian's interpreter, where python3-rosbag lives (a python3 earlier on PATH,
// e.g. from pyenv, does not see it).
std::string RunPython(const std::string& script) {
  const fs::path file = TempDir() / "read_bag.py";
  std::ofstream(file) << script;
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  std::string out;
  FILE* pipe = ::popen((python + " " + file.string() + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return "popen failed";
  char buf[4096];
  while (std::fgets(buf, sizeof(buf), pipe) != nullptr) out += buf;
  ::pclose(pipe);
  return out;
}

class SimulatedBag : public ::testing::Test {
 protected:
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(TempDir(), ec);
  }
};

TEST_F(SimulatedBag, Python3RosbagReadsIt) {
  if (RunPython("import rosbag\nprint('ok')\n").rfind("ok", 0) != 0)
    GTEST_SKIP() << "python3-rosbag is not installed";
  const SimOptions o = ShortTunnel();
  const std::string path = (TempDir() / "short.bag").string();
  const Written w = WriteSimulatedBag(o, path);
  ASSERT_EQ(w.scans.size(), 25u);
  ASSERT_EQ(w.imu.size(), 501u);
  const std::string out = RunPython(
      "import rosbag\n"
      "bag = rosbag.Bag('" +
      path +
      "')\n"
      "counts = {}\n"
      "for topic, msg, t in bag.read_messages():\n"
      "    counts[topic] = counts.get(topic, 0) + 1\n"
      "    if topic == '/os_cloud_node/points' and counts[topic] == 1:\n"
      "        print('cloud', msg.height, msg.width, msg.point_step, ','.join(f.name for f in "
      "msg.fields))\n"
      "    if topic == '/imu/data' and counts[topic] == 1:\n"
      "        print('imu_z', repr(msg.linear_acceleration.z))\n"
      "for k in sorted(counts): print(k, counts[k])\n");
  EXPECT_NE(out.find("/imu/data 501"), std::string::npos) << out;
  EXPECT_NE(out.find("/os_cloud_node/points 25"), std::string::npos) << out;
  EXPECT_NE(out.find("cloud 32 128"), std::string::npos) << out;
  EXPECT_NE(out.find("x,y,z,intensity,t,reflectivity,ring,ambient,range"), std::string::npos)
      << out;
  // At rest the accelerometer reads gravity plus the configured bias (plus
  // white noise of std accel_noise_density * sqrt(rate) = 0.03 m/s^2).
  const size_t at = out.find("imu_z ");
  ASSERT_NE(at, std::string::npos) << out;
  const double z = std::stod(out.substr(at + 6));
  EXPECT_NEAR(z, w.imu.front().acc_imu.z(), 1e-9);
  EXPECT_NEAR(z, o.imu.gravity + o.imu.accel_bias[2], 0.15);
}

// Reading the bag back with the library's reader returns the simulated data:
// the same IMU samples, and every return of every scan with its absolute time.
TEST_F(SimulatedBag, SensorBagReaderReturnsTheSimulatedData) {
  SimOptions o = ShortTunnel();
  o.duration = 1.0;
  const std::string path = (TempDir() / "roundtrip.bag").string();
  const Written w = WriteSimulatedBag(o, path);
  LidarOptions lidar;
  lidar.min_range = 0.0;
  lidar.max_range = 1000.0;
  ImuOptions imu;
  auto reader = SensorBagReader::Open(path, lidar, imu);
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  EXPECT_EQ((*reader)->lidar_layout(), "ouster");
  size_t n_imu = 0, n_scan = 0;
  for (;;) {
    ImuSample m;
    Scan s;
    StatusOr<SensorMessage> kind = (*reader)->Next(&m, &s);
    ASSERT_TRUE(kind.ok()) << kind.status().message();
    if (*kind == SensorMessage::kEnd) break;
    if (*kind == SensorMessage::kImu) {
      ASSERT_LT(n_imu, w.imu.size());
      EXPECT_EQ(m.t_ns, w.imu[n_imu].t_ns);
      EXPECT_LT((m.acc_imu - w.imu[n_imu].acc_imu).norm(), 1e-12);
      EXPECT_LT((m.gyro_imu - w.imu[n_imu].gyro_imu).norm(), 1e-12);
      ++n_imu;
      continue;
    }
    ASSERT_LT(n_scan, w.scans.size());
    const Scan& ref = w.scans[n_scan++];
    std::vector<const LidarPoint*> returns;
    for (const LidarPoint& p : ref.points)
      if (!p.p_lidar.isZero()) returns.push_back(&p);
    ASSERT_EQ(s.points.size(), returns.size());
    for (size_t i = 0; i < returns.size(); ++i) {
      EXPECT_EQ(s.points[i].p_lidar, returns[i]->p_lidar);
      EXPECT_EQ(s.points[i].t_ns, returns[i]->t_ns);
      EXPECT_EQ(s.points[i].ring, returns[i]->ring);
    }
  }
  EXPECT_EQ(n_imu, w.imu.size());
  EXPECT_EQ(n_scan, w.scans.size());
}

}  // namespace
}  // namespace rvlio

// SensorBagWriter (message layout, atomic write, bad input), python3-rosbag
// interoperability and ReadBagInfo.
#include <cstdlib>
#include <sstream>

#include <gtest/gtest.h>
#include <rosbag/view.h>

#include "bag_fixture.h"

namespace rvlio::test {
namespace {

const std::string kWriterCloudTopic = "/os_cloud_node/points";
const std::string kWriterImuTopic = "/imu/data";
namespace fs = std::filesystem;

class BagWriterTest : public TempDirTest {
 protected:
  // 5 organized sweeps (8 x 64) and 200 Hz IMU over 0.5 s.
  std::string WriteSample(const std::string& name) {
    const std::string path = Path(name);
    auto writer = SensorBagWriter::Create(path);
    EXPECT_TRUE(writer.ok());
    for (int k = 0; k < 5; ++k) {
      scans_.push_back(SyntheticScan(kT0 + k * 100 * kMs, 8, 64, k));
      EXPECT_TRUE((*writer)->WriteOusterScan(kWriterCloudTopic, "os_lidar", scans_.back(), 8, 64).ok());
    }
    for (int i = 0; i < 100; ++i) {
      ImuSample s;
      s.t_ns = kT0 + i * 5 * kMs;
      s.acc_imu = Eigen::Vector3d(0.5, -0.25, 9.75);
      s.gyro_imu = Eigen::Vector3d(0.125, 0.0, -0.5);
      EXPECT_TRUE((*writer)->WriteImu(kWriterImuTopic, "imu_link", s).ok());
    }
    EXPECT_TRUE((*writer)->Close().ok());
    return path;
  }
  std::vector<Scan> scans_;
};

TEST_F(BagWriterTest, OusterMessageLayoutAndTimes) {
  const std::string path = WriteSample("layout.bag");
  rosbag::Bag bag;
  bag.open(path, rosbag::bagmode::Read);
  rosbag::View clouds(bag, rosbag::TopicQuery(kWriterCloudTopic));
  ASSERT_EQ(clouds.size(), 5u);
  int k = 0;
  for (const rosbag::MessageInstance& m : clouds) {
    auto msg = m.instantiate<sensor_msgs::PointCloud2>();
    ASSERT_TRUE(msg);
    EXPECT_EQ(TimeNs(msg->header.stamp.toNSec()), scans_[k].t_start_ns);
    EXPECT_EQ(TimeNs(m.getTime().toNSec()), scans_[k].t_end_ns);  // recorded at the sweep end
    EXPECT_EQ(msg->header.frame_id, "os_lidar");
    EXPECT_EQ(msg->height, 8u);
    EXPECT_EQ(msg->width, 64u);
    EXPECT_EQ(msg->point_step, 48u);
    EXPECT_EQ(msg->row_step, 48u * 64);
    EXPECT_FALSE(msg->is_bigendian);
    EXPECT_EQ(msg->data.size(), 48u * 64 * 8);
    const std::vector<std::tuple<std::string, uint32_t, uint8_t>> expect = {
        {"x", 0, 7}, {"y", 4, 7}, {"z", 8, 7}, {"intensity", 16, 7}, {"t", 20, 6},
        {"reflectivity", 24, 4}, {"ring", 26, 4}, {"ambient", 28, 4}, {"range", 32, 6}};
    ASSERT_EQ(msg->fields.size(), expect.size());
    for (size_t f = 0; f < expect.size(); ++f) {
      EXPECT_EQ(msg->fields[f].name, std::get<0>(expect[f]));
      EXPECT_EQ(msg->fields[f].offset, std::get<1>(expect[f]));
      EXPECT_EQ(msg->fields[f].datatype, std::get<2>(expect[f]));
      EXPECT_EQ(msg->fields[f].count, 1u);
    }
    // Point 66 (row 1, column 2): t, ring and range in mm.
    const LidarPoint& p = scans_[k].points[66];
    ASSERT_TRUE(Valid(p));
    const uint8_t* d = msg->data.data() + 66 * 48;
    uint32_t t = 0, range_mm = 0;
    uint16_t ring = 0;
    std::memcpy(&t, d + 20, 4);
    std::memcpy(&ring, d + 26, 2);
    std::memcpy(&range_mm, d + 32, 4);
    EXPECT_EQ(TimeNs(t), p.t_ns - scans_[k].t_start_ns);
    EXPECT_EQ(ring, 1);
    EXPECT_NEAR(range_mm, 1000.0 * p.p_lidar.norm(), 0.5);
    ++k;
  }
  rosbag::View imus(bag, rosbag::TopicQuery(kWriterImuTopic));
  ASSERT_EQ(imus.size(), 100u);
  auto imu = imus.begin()->instantiate<sensor_msgs::Imu>();
  ASSERT_TRUE(imu);
  EXPECT_EQ(imu->orientation_covariance[0], -1.0);
  EXPECT_EQ(imu->linear_acceleration.z, 9.75);
  EXPECT_EQ(imu->angular_velocity.x, 0.125);
  EXPECT_EQ(imu->header.frame_id, "imu_link");
  EXPECT_EQ(TimeNs(imu->header.stamp.toNSec()), kT0);
}

TEST_F(BagWriterTest, UnorganizedWhenSizeDoesNotMatchRowsTimesCols) {
  const std::string path = Path("flat.bag");
  auto writer = SensorBagWriter::Create(path);
  ASSERT_TRUE(writer.ok());
  Scan s = SyntheticScan(kT0, 2, 10, 0);
  ASSERT_TRUE((*writer)->WriteOusterScan(kWriterCloudTopic, "l", s, 3, 10).ok());
  ASSERT_TRUE((*writer)->Close().ok());
  rosbag::Bag bag;
  bag.open(path, rosbag::bagmode::Read);
  rosbag::View v(bag);
  auto msg = v.begin()->instantiate<sensor_msgs::PointCloud2>();
  ASSERT_TRUE(msg);
  EXPECT_EQ(msg->height, 1u);
  EXPECT_EQ(msg->width, 20u);
}

TEST_F(BagWriterTest, WritesToTempAndRenamesOnClose) {
  const std::string path = Path("atomic.bag");
  {
    auto writer = SensorBagWriter::Create(path);
    ASSERT_TRUE(writer.ok());
    ImuSample s;
    s.t_ns = kT0;
    ASSERT_TRUE((*writer)->WriteImu(kWriterImuTopic, "imu", s).ok());
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(fs::exists(path + ".tmp"));
    ASSERT_TRUE((*writer)->Close().ok());
    EXPECT_TRUE(fs::exists(path));
    EXPECT_FALSE(fs::exists(path + ".tmp"));
    EXPECT_FALSE((*writer)->Close().ok());  // twice is a programmer's slip, not a crash
    EXPECT_FALSE((*writer)->WriteImu(kWriterImuTopic, "imu", s).ok());
  }
  const std::string abandoned = Path("abandoned.bag");
  {
    auto writer = SensorBagWriter::Create(abandoned);
    ASSERT_TRUE(writer.ok());
    ImuSample s;
    s.t_ns = kT0;
    ASSERT_TRUE((*writer)->WriteImu(kWriterImuTopic, "imu", s).ok());
  }  // destroyed without Close: no half bag left
  EXPECT_FALSE(fs::exists(abandoned));
  EXPECT_FALSE(fs::exists(abandoned + ".tmp"));

  auto nowhere = SensorBagWriter::Create(Path("no/such/dir/x.bag"));
  ASSERT_FALSE(nowhere.ok());
  EXPECT_NE(nowhere.status().message().find("no/such/dir/x.bag.tmp"), std::string::npos);
}

TEST_F(BagWriterTest, RejectsTimesRosCannotHold) {
  auto writer = SensorBagWriter::Create(Path("bad.bag"));
  ASSERT_TRUE(writer.ok());
  ImuSample s;
  s.t_ns = -1;
  Status st = (*writer)->WriteImu(kWriterImuTopic, "imu", s);
  EXPECT_EQ(st.code(), StatusCode::kInvalidInput);
  EXPECT_NE(st.message().find("IMU stamp -1 ns"), std::string::npos) << st.message();
  s.t_ns = 0;  // allowed: recorded at the smallest bag time
  EXPECT_TRUE((*writer)->WriteImu(kWriterImuTopic, "imu", s).ok());

  Scan scan = SyntheticScan(kT0, 2, 8, 0);
  scan.points[1].t_ns = kT0 - 1;  // before the sweep start
  st = (*writer)->WriteOusterScan(kWriterCloudTopic, "l", scan, 2, 8);
  EXPECT_EQ(st.code(), StatusCode::kInvalidInput);
  EXPECT_NE(st.message().find("point 1"), std::string::npos) << st.message();
  scan = SyntheticScan(kT0, 2, 8, 0);
  scan.t_end_ns = kT0 - 1;
  EXPECT_FALSE((*writer)->WriteOusterScan(kWriterCloudTopic, "l", scan, 2, 8).ok());
  EXPECT_TRUE((*writer)->Close().ok());
}

// python3-rosbag (the ROS tools' reader) must accept what the writer makes.
TEST_F(BagWriterTest, Python3RosbagReadsTheBag) {
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  if (std::system((python + " -c 'import rosbag' >/dev/null 2>&1").c_str()) != 0)
    GTEST_SKIP() << "python3-rosbag is not installed";
  const std::string path = WriteSample("py.bag");
  const std::string script = Path("read.py"), out = Path("out.txt");
  WriteAll(script,
           "import sys, rosbag\n"
           "b = rosbag.Bag(sys.argv[1])\n"
           "counts = {}\n"
           "first = {}\n"
           "for topic, msg, t in b.read_messages():\n"
           "    counts[topic] = counts.get(topic, 0) + 1\n"
           "    first.setdefault(topic, (msg, t))\n"
           "print('total', b.get_message_count())\n"
           "for topic in sorted(counts): print('count', topic, counts[topic])\n"
           "cloud, t = first['/os_cloud_node/points']\n"
           "print('cloud', cloud.header.stamp.to_nsec(), t.to_nsec(), cloud.height, cloud.width,\n"
           "      cloud.point_step, ','.join(f.name for f in cloud.fields))\n"
           "imu, t = first['/imu/data']\n"
           "print('imu', imu.header.stamp.to_nsec(), imu.orientation_covariance[0],\n"
           "      imu.linear_acceleration.z)\n");
  const std::string cmd = python + " " + script + " " + path + " > " + out + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << ReadAll(out);
  std::istringstream lines(ReadAll(out));
  std::string text = lines.str();
  EXPECT_NE(text.find("total 105\n"), std::string::npos) << text;
  EXPECT_NE(text.find("count /imu/data 100\n"), std::string::npos) << text;
  EXPECT_NE(text.find("count /os_cloud_node/points 5\n"), std::string::npos) << text;
  std::ostringstream cloud;
  cloud << "cloud " << kT0 << " " << kT0 + 99 * kMs
        << " 8 64 48 x,y,z,intensity,t,reflectivity,ring,ambient,range\n";
  EXPECT_NE(text.find(cloud.str()), std::string::npos) << text;
  std::ostringstream imu;
  imu << "imu " << kT0 << " -1.0 9.75\n";
  EXPECT_NE(text.find(imu.str()), std::string::npos) << text;
}

TEST_F(BagWriterTest, BagInfoListsTopicsRatesAndLayout) {
  const std::string path = WriteSample("info.bag");
  StatusOr<BagInfo> info = ReadBagInfo(path);
  ASSERT_TRUE(info.ok()) << info.status().message();
  EXPECT_EQ(info->path, path);
  EXPECT_EQ(info->messages, 105);
  EXPECT_NEAR(info->start_s, NsToSeconds(kT0), 1e-6);
  EXPECT_EQ(info->start_ns, kT0);
  EXPECT_EQ(info->end_ns, kT0 + 499 * kMs);  // the last sweep is recorded at its end
  ASSERT_EQ(info->topics.size(), 2u);
  const BagTopicInfo& imu = info->topics[0];  // sorted by name
  const BagTopicInfo& cloud = info->topics[1];
  EXPECT_EQ(imu.topic, kWriterImuTopic);
  EXPECT_EQ(imu.type, "sensor_msgs/Imu");
  EXPECT_EQ(imu.count, 100);
  EXPECT_NEAR(imu.rate_hz, 200.0, 1e-6);
  EXPECT_TRUE(imu.lidar_layout.empty());
  EXPECT_EQ(cloud.type, "sensor_msgs/PointCloud2");
  EXPECT_EQ(cloud.count, 5);
  EXPECT_NEAR(cloud.rate_hz, 10.0, 1e-6);
  EXPECT_EQ(cloud.lidar_layout, "ouster");
  EXPECT_EQ(cloud.header_stamp, "start");
  EXPECT_TRUE(cloud.decode_error.empty());
  EXPECT_EQ(cloud.fields, (std::vector<std::string>{"x", "y", "z", "intensity", "t",
                                                    "reflectivity", "ring", "ambient", "range"}));
  double valid = 0;
  for (const Scan& s : scans_)
    for (const LidarPoint& p : s.points) valid += Valid(p);
  EXPECT_EQ(cloud.scans_sampled, 5);
  EXPECT_DOUBLE_EQ(cloud.points_per_scan, valid / 5.0);

  StatusOr<BagInfo> wrong = ReadBagInfo(path, kWriterImuTopic);
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.status().message().find("expected sensor_msgs/PointCloud2"), std::string::npos);
  StatusOr<BagInfo> missing = ReadBagInfo(path, "/points");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("/imu/data (sensor_msgs/Imu)"), std::string::npos);
  StatusOr<BagInfo> only = ReadBagInfo(path, kWriterCloudTopic);
  ASSERT_TRUE(only.ok());
  EXPECT_EQ(only->topics[1].lidar_layout, "ouster");

  StatusOr<BagInfo> absent = ReadBagInfo(Path("absent.bag"));
  ASSERT_FALSE(absent.ok());
  EXPECT_EQ(absent.status().code(), StatusCode::kInvalidInput);
}

TEST_F(BagWriterTest, BagInfoReportsCloudsItCannotDecode) {
  RawCloud c = MakeCloud({{"x", 0, kPointFloat32, 1}, {"y", 4, kPointFloat32, 1},
                          {"z", 8, kPointFloat32, 1}},
                         12, "", "");
  c.stamp_ns = kT0;
  c.Resize(3);
  const std::string path = Path("xyz.bag");
  {
    rosbag::Bag bag;
    bag.open(path, rosbag::bagmode::Write);
    bag.write("/points", RosTime(kT0), ToMsg(c));
    bag.close();
  }
  StatusOr<BagInfo> info = ReadBagInfo(path);
  ASSERT_TRUE(info.ok()) << info.status().message();
  ASSERT_EQ(info->topics.size(), 1u);
  EXPECT_EQ(info->topics[0].lidar_layout, "unknown");
  EXPECT_NE(info->topics[0].decode_error.find("no per-point time field; fields are x,y,z"),
            std::string::npos) << info->topics[0].decode_error;
  EXPECT_EQ(info->topics[0].rate_hz, 0.0);  // one message: no rate
}

}  // namespace
}  // namespace rvlio::test

// SensorBagReader on bags generated at run time: the four layouts, IMU
// handling, ordering, and clean errors for bad files.
#include <gtest/gtest.h>

#include "bag_fixture.h"

namespace rvlio::test {
namespace {

const std::string kCloudTopic = "/os_cloud_node/points";
const std::string kImuTopic = "/imu/data";

class BagReaderTest : public TempDirTest {
 protected:
  // IMU at 200 Hz over [t0 - 50 ms, t0 + 350 ms] and three Ouster sweeps.
  std::string WriteOusterBag(const std::string& name, std::vector<Scan>* scans) {
    const std::string path = Path(name);
    auto writer = SensorBagWriter::Create(path);
    EXPECT_TRUE(writer.ok()) << writer.status().message();
    for (int k = 0; k < 3; ++k) {
      scans->push_back(SyntheticScan(kT0 + k * 100 * kMs, 4, 32, k));
      EXPECT_TRUE((*writer)->WriteOusterScan(kCloudTopic, "os_lidar", scans->back(), 4, 32).ok());
    }
    for (int i = 0; i <= 80; ++i) {
      ImuSample s;
      s.t_ns = kT0 - 50 * kMs + i * 5 * kMs;
      s.acc_imu = Eigen::Vector3d(0.01 * i, -0.02 * i, 9.8);
      s.gyro_imu = Eigen::Vector3d(0.001 * i, 0.0, -0.003 * i);
      EXPECT_TRUE((*writer)->WriteImu(kImuTopic, "imu", s).ok());
    }
    EXPECT_TRUE((*writer)->Close().ok());
    return path;
  }

  // Writes clouds (and a 200 Hz IMU) with rosbag directly; each cloud is
  // recorded at its latest point time.
  std::string WriteRawBag(const std::string& name, const std::vector<RawCloud>& clouds,
                          const std::vector<TimeNs>& record_times) {
    const std::string path = Path(name);
    rosbag::Bag bag;
    bag.open(path, rosbag::bagmode::Write);
    for (size_t k = 0; k < clouds.size(); ++k)
      bag.write(kCloudTopic, RosTime(record_times[k]), ToMsg(clouds[k]));
    for (int i = 0; i < 80; ++i) {
      const TimeNs t = kT0 - 50 * kMs + i * 5 * kMs;
      bag.write(kImuTopic, RosTime(t), ImuMsg(t, 0, 0, 9.8));
    }
    bag.close();
    return path;
  }

  // Three sweeps of n pattern points in a driver layout; time_of(k, i) is the
  // field value of point i of sweep k, abs_ns(k, i) the absolute time it means.
  template <typename TimeOf, typename AbsNs>
  void CheckThirdParty(RawCloud proto, const std::string& layout, TimeNs stamp_offset,
                       TimeOf time_of, AbsNs abs_ns, double tol_ns, const std::string& bag_name) {
    const uint32_t n = 300;
    std::vector<RawCloud> clouds;
    std::vector<TimeNs> record;
    for (int k = 0; k < 3; ++k) {
      RawCloud c = proto;
      c.stamp_ns = kT0 + k * 100 * kMs + stamp_offset;
      c.Resize(n);
      for (uint32_t i = 0; i < n; ++i) {
        const double a = 2.0 * M_PI * i / n;
        c.SetPoint(i, 4.0 * std::cos(a), 4.0 * std::sin(a), 0.01 * k, i, time_of(k, i), i % 32);
      }
      clouds.push_back(c);
      record.push_back(kT0 + k * 100 * kMs + 100 * kMs);
    }
    const std::string path = WriteRawBag(bag_name, clouds, record);
    ReadResult r = ReadEverything(path, LidarOn(kCloudTopic), ImuOn(kImuTopic));
    ASSERT_TRUE(r.error.ok()) << r.error.message();
    EXPECT_EQ(r.layout, layout);
    ASSERT_EQ(r.scans.size(), 3u) << layout;
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(r.scans[k].points.size(), n);
      for (uint32_t i = 0; i < n; ++i) {
        const LidarPoint& p = r.scans[k].points[i];
        const double a = 2.0 * M_PI * i / n;
        EXPECT_EQ(p.p_lidar.x(), float(4.0 * std::cos(a)));
        EXPECT_EQ(p.p_lidar.z(), float(0.01 * k));
        EXPECT_EQ(p.ring, i % 32);
        EXPECT_NEAR(double(p.t_ns - kT0), double(abs_ns(k, i) - kT0), tol_ns) << layout << k << i;
      }
    }
    EXPECT_EQ(r.imu.size(), 80u);
  }
};

TEST_F(BagReaderTest, OusterRoundTripKeepsPointsTimesAndOrder) {
  std::vector<Scan> written;
  const std::string path = WriteOusterBag("ouster.bag", &written);
  ReadResult r = ReadEverything(path, LidarOn(kCloudTopic), ImuOn(kImuTopic));
  ASSERT_TRUE(r.error.ok()) << r.error.message();
  EXPECT_EQ(r.layout, "ouster");
  ASSERT_EQ(r.imu.size(), 81u);
  for (size_t i = 0; i < r.imu.size(); ++i) {
    EXPECT_EQ(r.imu[i].t_ns, kT0 - 50 * kMs + TimeNs(i) * 5 * kMs);
    EXPECT_DOUBLE_EQ(r.imu[i].acc_imu.x(), 0.01 * i);
    EXPECT_DOUBLE_EQ(r.imu[i].acc_imu.y(), -0.02 * i);
    EXPECT_DOUBLE_EQ(r.imu[i].gyro_imu.z(), -0.003 * i);
  }
  ASSERT_EQ(r.scans.size(), 3u);
  int64_t dropped = 0;
  for (size_t k = 0; k < 3; ++k) {
    std::vector<LidarPoint> expect;
    for (const auto& p : written[k].points) {
      if (Valid(p)) expect.push_back(p);
      else ++dropped;
    }
    const Scan& got = r.scans[k];
    ASSERT_EQ(got.points.size(), expect.size());
    for (size_t i = 0; i < expect.size(); ++i) {
      EXPECT_EQ(got.points[i].p_lidar, expect[i].p_lidar);
      EXPECT_EQ(got.points[i].t_ns, expect[i].t_ns);
      EXPECT_EQ(got.points[i].ring, expect[i].ring);
      EXPECT_FLOAT_EQ(got.points[i].intensity, expect[i].intensity);
    }
    // Times come from the points: the first column has a no-return point in
    // row 0 only, so the earliest kept time is still the sweep start.
    EXPECT_EQ(got.t_start_ns, written[k].t_start_ns);
    EXPECT_EQ(got.t_end_ns, written[k].t_start_ns + 99 * kMs);
    // The sweep is recorded at its end: every IMU sample up to then came first.
    EXPECT_LE(r.last_imu_before_scan[k], got.t_end_ns);
    EXPECT_GE(r.last_imu_before_scan[k], got.t_end_ns - 5 * kMs);
  }
  EXPECT_EQ(r.stats.invalid_points, dropped);
  EXPECT_EQ(r.stats.scans, 3);
  EXPECT_EQ(r.stats.imu_samples, 81);
  EXPECT_EQ(r.stats.imu_gaps, 0);
  EXPECT_NEAR(r.stats.imu_max_gap_s, 0.005, 1e-12);
}

TEST_F(BagReaderTest, OusterHeaderStampForcedEnd) {
  std::vector<Scan> written;
  const std::string path = WriteOusterBag("ouster_end.bag", &written);
  LidarOptions lidar = LidarOn(kCloudTopic);
  lidar.header_stamp = "end";
  ReadResult r = ReadEverything(path, lidar, ImuOn(kImuTopic));
  ASSERT_TRUE(r.error.ok()) << r.error.message();
  ASSERT_EQ(r.scans.size(), 3u);
  // Read as if the stamp (the sweep start) were the end: shifted back by 99 ms.
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(r.scans[k].t_end_ns, written[k].t_start_ns);
    EXPECT_EQ(r.scans[k].t_start_ns, written[k].t_start_ns - 99 * kMs);
  }
}

TEST_F(BagReaderTest, VelodyneStampAtEndWithNegativeTimes) {
  // Stamp at the sweep end (t0 + 100 k ms + 99 ms), time in [-99 ms, 0].
  CheckThirdParty(
      VelodyneCloud(), "velodyne", 99 * kMs,
      [](int, uint32_t i) { return -0.099 + 0.099 * i / 299.0; },
      [](int k, uint32_t i) {
        return kT0 + k * 100 * kMs + 99 * kMs +
               std::llround(double(float(-0.099 + 0.099 * i / 299.0)) * 1e9);
      },
      0.0, "velodyne.bag");
}

TEST_F(BagReaderTest, HesaiAbsoluteSeconds) {
  CheckThirdParty(
      HesaiCloud(), "hesai", 0,
      [](int k, uint32_t i) { return NsToSeconds(kT0 + k * 100 * kMs + TimeNs(i) * 330000); },
      [](int k, uint32_t i) { return kT0 + k * 100 * kMs + TimeNs(i) * 330000; }, 500.0,
      "hesai.bag");
}

TEST_F(BagReaderTest, LivoxAbsoluteNanoseconds) {
  CheckThirdParty(
      LivoxCloud(), "livox", 0,
      [](int k, uint32_t i) { return double(kT0 + k * 100 * kMs + TimeNs(i) * 330000); },
      [](int k, uint32_t i) { return kT0 + k * 100 * kMs + TimeNs(i) * 330000; }, 500.0,
      "livox.bag");
}

TEST_F(BagReaderTest, LivoxOffsetTime) {
  CheckThirdParty(
      LivoxOffsetCloud(), "livox", 0,
      [](int, uint32_t i) { return double(TimeNs(i) * 330000); },
      [](int k, uint32_t i) { return kT0 + k * 100 * kMs + TimeNs(i) * 330000; }, 0.0,
      "livox_offset.bag");
}

TEST_F(BagReaderTest, CompressedBagsReadLikeUncompressed) {
  RawCloud c = OusterCloud();
  c.stamp_ns = kT0;
  c.Resize(50);
  for (uint32_t i = 0; i < 50; ++i) c.SetPoint(i, 1.0 + i, -2.0, 0.5, i, 1000.0 * i, i % 4);
  for (auto compression : {rosbag::compression::BZ2, rosbag::compression::LZ4}) {
    const std::string path = Path("compressed.bag");
    {
      rosbag::Bag bag;
      bag.open(path, rosbag::bagmode::Write);
      bag.setCompression(compression);
      for (int i = 0; i < 30; ++i) {
        const TimeNs t = kT0 + i * 5 * kMs;
        bag.write(kImuTopic, RosTime(t), ImuMsg(t, 0.5, 0, 9.8));
      }
      bag.write(kCloudTopic, RosTime(kT0 + 100 * kMs), ToMsg(c));
      bag.close();
    }
    ReadResult r = ReadEverything(path, LidarOn(kCloudTopic), ImuOn(kImuTopic));
    ASSERT_TRUE(r.error.ok()) << r.error.message();
    EXPECT_EQ(r.imu.size(), 30u);
    ASSERT_EQ(r.scans.size(), 1u);
    ASSERT_EQ(r.scans[0].points.size(), 50u);
    EXPECT_EQ(r.scans[0].points[49].p_lidar.x(), 50.0f);
    EXPECT_EQ(r.scans[0].points[49].t_ns, kT0 + 49000);
  }
}

TEST_F(BagReaderTest, EmptyScansAreSkippedAndCounted) {
  const std::string path = Path("empty.bag");
  auto writer = SensorBagWriter::Create(path);
  ASSERT_TRUE(writer.ok());
  Scan empty = SyntheticScan(kT0, 2, 8, 0);
  for (auto& p : empty.points) p.p_lidar.setZero();
  Scan full = SyntheticScan(kT0 + 100 * kMs, 2, 8, 0);
  ASSERT_TRUE((*writer)->WriteOusterScan(kCloudTopic, "l", empty, 2, 8).ok());
  ASSERT_TRUE((*writer)->WriteOusterScan(kCloudTopic, "l", full, 2, 8).ok());
  ImuSample s;
  s.t_ns = kT0;
  ASSERT_TRUE((*writer)->WriteImu(kImuTopic, "imu", s).ok());
  ASSERT_TRUE((*writer)->Close().ok());
  ReadResult r = ReadEverything(path, LidarOn(kCloudTopic), ImuOn(kImuTopic));
  ASSERT_TRUE(r.error.ok()) << r.error.message();
  ASSERT_EQ(r.scans.size(), 1u);
  EXPECT_EQ(r.scans[0].t_start_ns, kT0 + 100 * kMs);
  EXPECT_EQ(r.stats.empty_scans, 1);
  EXPECT_EQ(r.stats.scans, 1);
}

TEST_F(BagReaderTest, ImuInGIsScaledToSi) {
  const std::string path = Path("imu_g.bag");
  auto writer = SensorBagWriter::Create(path);
  ASSERT_TRUE(writer.ok());
  for (int i = 0; i < 10; ++i) {
    ImuSample s;
    s.t_ns = kT0 + i * 10 * kMs;
    s.acc_imu = Eigen::Vector3d(0.1 * i, -0.5, 1.0);
    s.gyro_imu = Eigen::Vector3d(0.3, 0.2, 0.1 * i);
    ASSERT_TRUE((*writer)->WriteImu(kImuTopic, "imu", s).ok());
  }
  ASSERT_TRUE((*writer)->WriteOusterScan(kCloudTopic, "l", SyntheticScan(kT0, 2, 8, 0), 2, 8).ok());
  ASSERT_TRUE((*writer)->Close().ok());
  ImuOptions imu = ImuOn(kImuTopic);
  imu.accel_unit = "g";
  ReadResult r = ReadEverything(path, LidarOn(kCloudTopic), imu);
  ASSERT_TRUE(r.error.ok()) << r.error.message();
  ASSERT_EQ(r.imu.size(), 10u);
  for (int i = 0; i < 10; ++i) {
    EXPECT_NEAR(r.imu[i].acc_imu.x(), 0.1 * i * 9.80665, 1e-12);
    EXPECT_NEAR(r.imu[i].acc_imu.y(), -0.5 * 9.80665, 1e-12);
    EXPECT_NEAR(r.imu[i].acc_imu.z(), 9.80665, 1e-12);
    EXPECT_DOUBLE_EQ(r.imu[i].gyro_imu.z(), 0.1 * i);  // gyro untouched
  }
}

TEST_F(BagReaderTest, DuplicateNonMonotonicAndGappyImuStamps) {
  // Recorded in order, but the header stamps repeat, go back and jump.
  const std::vector<TimeNs> stamps_ms = {0, 5, 5, 10, 8, 15, 200, 205, 205, 203, 210};
  const std::string path = Path("imu_bad.bag");
  {
    rosbag::Bag bag;
    bag.open(path, rosbag::bagmode::Write);
    for (size_t i = 0; i < stamps_ms.size(); ++i) {
      const double nan = std::nan("");
      sensor_msgs::Imu m = ImuMsg(kT0 + stamps_ms[i] * kMs, double(i), 0, 9.8);
      bag.write(kImuTopic, RosTime(kT0 + TimeNs(i) * kMs), m);
      if (i == 3)  // a NaN sample between them
        bag.write(kImuTopic, RosTime(kT0 + TimeNs(i) * kMs + 1),
                  ImuMsg(kT0 + 12 * kMs, nan, 0, 9.8));
    }
    RawCloud c = OusterCloud();
    c.stamp_ns = kT0;
    c.Resize(1);
    c.SetPoint(0, 1, 2, 3, 0, 0, 0);
    bag.write(kCloudTopic, RosTime(kT0 + 300 * kMs), ToMsg(c));
    bag.close();
  }
  ImuOptions imu = ImuOn(kImuTopic);
  imu.max_gap = 0.1;
  ReadResult r = ReadEverything(path, LidarOn(kCloudTopic), imu);
  ASSERT_TRUE(r.error.ok()) << r.error.message();
  std::vector<TimeNs> kept;
  for (const auto& s : r.imu) kept.push_back((s.t_ns - kT0) / kMs);
  EXPECT_EQ(kept, (std::vector<TimeNs>{0, 5, 10, 15, 200, 205, 210}));
  EXPECT_EQ(r.stats.imu_duplicates, 2);
  EXPECT_EQ(r.stats.imu_non_monotonic, 2);
  EXPECT_EQ(r.stats.imu_invalid, 1);
  EXPECT_EQ(r.stats.imu_gaps, 1);
  EXPECT_NEAR(r.stats.imu_max_gap_s, 0.185, 1e-12);
  EXPECT_EQ(r.stats.imu_samples, 7);
  ASSERT_EQ(r.scans.size(), 1u);
}

TEST_F(BagReaderTest, MissingOrWrongTopicListsTheTopics) {
  std::vector<Scan> written;
  const std::string path = WriteOusterBag("topics.bag", &written);
  auto missing = SensorBagReader::Open(path, LidarOn("/velodyne_points"), ImuOn(kImuTopic));
  ASSERT_FALSE(missing.ok());
  const std::string& msg = missing.status().message();
  EXPECT_EQ(missing.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(msg.find("lidar.topic '/velodyne_points' is not in bag '" + path + "'"),
            std::string::npos) << msg;
  EXPECT_NE(msg.find("/imu/data (sensor_msgs/Imu)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("/os_cloud_node/points (sensor_msgs/PointCloud2)"), std::string::npos);

  auto wrong = SensorBagReader::Open(path, LidarOn(kCloudTopic), ImuOn(kCloudTopic));
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.status().message().find(
                "has type sensor_msgs/PointCloud2, expected sensor_msgs/Imu"),
            std::string::npos) << wrong.status().message();
}

TEST_F(BagReaderTest, CloudWithoutTimeFieldFailsAtOpen) {
  RawCloud c = MakeCloud({{"x", 0, kPointFloat32, 1}, {"y", 4, kPointFloat32, 1},
                          {"z", 8, kPointFloat32, 1}, {"intensity", 12, kPointFloat32, 1}},
                         16, "", "");
  c.stamp_ns = kT0;
  c.Resize(3);
  const std::string path = WriteRawBag("notime.bag", {c}, {kT0});
  auto reader = SensorBagReader::Open(path, LidarOn(kCloudTopic), ImuOn(kImuTopic));
  ASSERT_FALSE(reader.ok());
  EXPECT_NE(reader.status().message().find(
                "PointCloud2 on /os_cloud_node/points has no per-point time field; fields are "
                "x,y,z,intensity"),
            std::string::npos) << reader.status().message();
}

TEST_F(BagReaderTest, TruncatedBagIsACleanError) {
  // Enough data for several chunks (rosbag chunks are 768 KiB).
  const std::string full = Path("full.bag");
  {
    auto writer = SensorBagWriter::Create(full);
    ASSERT_TRUE(writer.ok());
    for (int k = 0; k < 40; ++k) {
      ASSERT_TRUE((*writer)->WriteOusterScan(kCloudTopic, "l",
                                             SyntheticScan(kT0 + k * 100 * kMs, 16, 128, k), 16,
                                             128).ok());
      for (int i = 0; i < 20; ++i) {
        ImuSample s;
        s.t_ns = kT0 + k * 100 * kMs + i * 5 * kMs;
        ASSERT_TRUE((*writer)->WriteImu(kImuTopic, "imu", s).ok());
      }
    }
    ASSERT_TRUE((*writer)->Close().ok());
  }
  const std::string bytes = ReadAll(full);
  ASSERT_GT(bytes.size(), 2u * 768 * 1024);
  for (double fraction : {0.0, 0.01, 0.25, 0.5, 0.75, 0.99}) {
    const std::string cut = Path("cut.bag");
    WriteAll(cut, bytes.substr(0, size_t(double(bytes.size()) * fraction)));
    ReadResult r = ReadEverything(cut, LidarOn(kCloudTopic), ImuOn(kImuTopic));
    ASSERT_FALSE(r.error.ok()) << "fraction " << fraction;
    EXPECT_EQ(r.error.code(), StatusCode::kInvalidInput);
    EXPECT_NE(r.error.message().find(cut), std::string::npos) << r.error.message();
  }
  WriteAll(Path("last.bag"), bytes.substr(0, bytes.size() - 1));
  EXPECT_FALSE(ReadEverything(Path("last.bag"), LidarOn(kCloudTopic), ImuOn(kImuTopic)).error.ok());
  // The intact bag reads completely.
  ReadResult ok = ReadEverything(full, LidarOn(kCloudTopic), ImuOn(kImuTopic));
  ASSERT_TRUE(ok.error.ok()) << ok.error.message();
  EXPECT_EQ(ok.scans.size(), 40u);
  EXPECT_EQ(ok.imu.size(), 800u);
}

TEST_F(BagReaderTest, NotABagMissingFileAndFolder) {
  const std::string text = Path("notes.bag");
  WriteAll(text, "this is not a ROS bag\n");
  auto a = SensorBagReader::Open(text, LidarOn(kCloudTopic), ImuOn(kImuTopic));
  ASSERT_FALSE(a.ok());
  EXPECT_EQ(a.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(a.status().message().find("'" + text + "' is not a readable ROS1 bag"),
            std::string::npos) << a.status().message();

  auto b = SensorBagReader::Open(Path("nope.bag"), LidarOn(kCloudTopic), ImuOn(kImuTopic));
  ASSERT_FALSE(b.ok());
  EXPECT_EQ(b.status().message(), "bag '" + Path("nope.bag") + "' does not exist");

  auto c = SensorBagReader::Open(dir_, LidarOn(kCloudTopic), ImuOn(kImuTopic));
  ASSERT_FALSE(c.ok());
  EXPECT_NE(c.status().message().find("not a regular file"), std::string::npos);

  WriteAll(Path("empty.bag"), "");
  EXPECT_FALSE(SensorBagReader::Open(Path("empty.bag"), LidarOn(kCloudTopic), ImuOn(kImuTopic)).ok());
}

}  // namespace
}  // namespace rvlio::test

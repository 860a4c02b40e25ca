// LiveSensorSource (formats/live_source.h): network messages in the order a
// recording of them gives, bounded queues that drop scans and never IMU
// samples, and the errors of a live input (wrong type, no message, stop).
#include <atomic>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "rvlio/formats/cdr.h"
#include "rvlio/formats/live_source.h"

namespace rvlio {
namespace {

constexpr TimeNs kMs = 1000000;
const auto kNow = std::chrono::steady_clock::now;

std::vector<uint8_t> Imu(TimeNs t_ns) {
  cdr::ImuMessage m;
  m.header_stamp_ns = t_ns;
  m.linear_acceleration = {0.0, 0.0, 9.81};
  return cdr::EncodeImu(m);
}

// A Livox CustomMsg sweeping from t_start_ns over 90 ms.
std::vector<uint8_t> Lidar(TimeNs t_start_ns) {
  Scan scan;
  scan.t_start_ns = t_start_ns;
  for (int i = 0; i < 100; ++i) {
    LidarPoint p;
    p.p_lidar = Eigen::Vector3f(5.0f, 0.01f * static_cast<float>(i), 1.0f);
    p.t_ns = t_start_ns + i * 90 * kMs / 99;
    scan.points.push_back(p);
  }
  scan.t_end_ns = scan.points.back().t_ns;
  return cdr::EncodeLivoxCustomMsg(ScanToLivoxCustomMsg(scan, "lidar"));
}

LiveSourceOptions Options() {
  LiveSourceOptions o;
  o.encoding = WireEncoding::kCdr;
  o.origin = "test";
  o.lidar.topic = "/points";
  o.imu.topic = "/imu";
  o.lidar.wait_timeout = 5.0;
  return o;
}

void PushImu(LiveSensorSource* s, TimeNs t_ns) {
  const std::vector<uint8_t> b = Imu(t_ns);
  ASSERT_TRUE(s->PushImu(b.data(), b.size(), cdr::kImuType).has_value());
}
void PushLidar(LiveSensorSource* s, TimeNs t_start_ns) {
  const std::vector<uint8_t> b = Lidar(t_start_ns);
  s->PushLidar(b.data(), b.size(), kLivoxRos2Type, kNow());
}

// What Next delivers: 'i' per IMU sample, 's' per scan, until nothing is ready.
std::string Drain(LiveSensorSource* s, int n) {
  std::string out;
  ImuSample imu;
  Scan scan;
  for (int i = 0; i < n; ++i) {
    StatusOr<SensorMessage> m = s->Next(&imu, &scan);
    EXPECT_TRUE(m.ok()) << m.status().message();
    if (!m.ok()) break;
    out += *m == SensorMessage::kImu ? 'i' : 's';
  }
  return out;
}

// A scan that arrives before the IMU samples of its sweep is delivered just
// before the first sample stamped at or after its end: a recording's order.
TEST(LiveSensorSource, ScanWaitsForTheImuSampleAfterItsEnd) {
  LiveSensorSource s(Options());
  PushImu(&s, 0);
  PushLidar(&s, 10 * kMs);  // ends at 100 ms
  for (TimeNs t = 50; t <= 150; t += 50) PushImu(&s, t * kMs);
  EXPECT_EQ(Drain(&s, 5), "iisii");
  EXPECT_EQ(s.live_stats().scans_dropped, 0);
  EXPECT_EQ(s.lidar_layout(), "livox_custom");
  const std::optional<LiveScanArrival> a = s.TakeArrival(100 * kMs);
  ASSERT_TRUE(a.has_value());
  EXPECT_EQ(a->t_end_ns, 100 * kMs);
  EXPECT_EQ(a->scan.points.size(), 100u);
}

// A scan decoded after its covering IMU sample arrived is not held for the next one.
TEST(LiveSensorSource, ScanAlreadyCoveredIsDeliveredAtOnce) {
  LiveSensorSource s(Options());
  PushImu(&s, 0);
  PushImu(&s, 100 * kMs);
  PushLidar(&s, 10 * kMs);  // ends at 100 ms
  EXPECT_EQ(Drain(&s, 3), "iis");
  const std::optional<LiveScanArrival> a = s.TakeArrival(100 * kMs);
  ASSERT_TRUE(a.has_value());
  EXPECT_GE(a->covered, a->arrival);
}

// The estimator fell behind: beyond live.scan_queue ready scans the oldest
// goes (counted); every IMU sample stays.
TEST(LiveSensorSource, DropsOldestScansNeverImu) {
  LiveSourceOptions o = Options();
  o.live.scan_queue = 2;
  LiveSensorSource s(o);
  PushImu(&s, 0);
  for (int k = 0; k < 5; ++k) {
    PushLidar(&s, k * 100 * kMs);
    PushImu(&s, (k * 100 + 95) * kMs);
  }
  EXPECT_EQ(s.live_stats().scans_dropped, 3);
  EXPECT_EQ(Drain(&s, 8), "iiiisisi");  // the last two scans, all six IMU samples
  EXPECT_EQ(s.live_stats().imu_dropped, 0);
}

TEST(LiveSensorSource, WrongTypeEndsTheInputNamingTheTopic) {
  LiveSensorSource s(Options());
  const std::vector<uint8_t> b = cdr::EncodeString("hello");
  s.PushLidar(b.data(), b.size(), cdr::kStringType, kNow());
  ImuSample imu;
  Scan scan;
  StatusOr<SensorMessage> m = s.Next(&imu, &scan);
  ASSERT_FALSE(m.ok());
  EXPECT_EQ(m.status().message(),
            "lidar.topic '/points' (test) carries std_msgs/msg/String, expected "
            "sensor_msgs/msg/PointCloud2 or livox_ros_driver2/msg/CustomMsg");
}

TEST(LiveSensorSource, NoMessageWithinWaitTimeoutNamesTheTopic) {
  LiveSourceOptions o = Options();
  o.lidar.wait_timeout = 0.1;
  LiveSensorSource s(o);
  PushImu(&s, 0);
  EXPECT_EQ(Drain(&s, 1), "i");
  ImuSample imu;
  Scan scan;
  StatusOr<SensorMessage> m = s.Next(&imu, &scan);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.status().message().find("no message on lidar.topic '/points' within "
                                      "lidar.wait_timeout 0.1 s (test)"),
            std::string::npos)
      << m.status().message();
}

TEST(LiveSensorSource, StopEndsTheInput) {
  std::atomic<bool> stop{false};
  LiveSourceOptions o = Options();
  o.stopped = [&stop] { return stop.load(); };
  LiveSensorSource s(o);
  std::thread stopper([&stop] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    stop = true;
  });
  ImuSample imu;
  Scan scan;
  StatusOr<SensorMessage> m = s.Next(&imu, &scan);
  stopper.join();
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(*m, SensorMessage::kEnd);
}

// The lidar.time_offset of a recording applies to live scans too.
TEST(LiveSensorSource, TimeOffsetMovesScansOntoTheImuClock) {
  LiveSourceOptions o = Options();
  o.lidar.time_offset = 0.02;
  LiveSensorSource s(o);
  PushImu(&s, 0);
  PushLidar(&s, 10 * kMs);
  PushImu(&s, 110 * kMs);  // the moved end is 120 ms: not yet
  PushImu(&s, 120 * kMs);
  EXPECT_EQ(Drain(&s, 4), "iisi");
}

}  // namespace
}  // namespace rvlio

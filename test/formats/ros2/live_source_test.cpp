// LiveSensorSource (formats/live_source.h): network messages in the order a
// recording of them gives, bounded queues that drop scans and never IMU
// samples, the errors of a live input (wrong type, no message, stop), and
// Ouster packets decoded as a packet recording's reader decodes them.
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <thread>

#include <gtest/gtest.h>

#include "cli/cli_util.h"
#include "rvlio/formats/cdr.h"
#include "rvlio/formats/live_source.h"
#include "rvlio/formats/ouster.h"
#include "rvlio/formats/sensor_bag.h"

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
  ASSERT_EQ(s->PushImu(b.data(), b.size(), cdr::kImuType).size(), 1u);
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
            "sensor_msgs/msg/PointCloud2, livox_ros_driver2/msg/CustomMsg, "
            "ouster_sensor_msgs/msg/PacketMsg or ouster_msgs/msg/PacketMsg");
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

// ---------------------------------------------------------------------------
// Ouster packets (a namespace of their own: test/formats/ros2 is one unity build)

namespace live_ouster {

constexpr const char* kLidarPackets = "/ouster/lidar_packets";
constexpr const char* kImuPackets = "/ouster/imu_packets";

// A small simulated sensor: 4 beams, 64 columns at 10 Hz (4 packets a frame).
OusterMetadata SmallSensor(std::vector<double> altitude_deg = {-15.0, -5.0, 5.0, 15.0}) {
  StatusOr<OusterMetadata> meta =
      SimulatedOusterMetadata(altitude_deg, 64, 10, Eigen::Isometry3d::Identity());
  EXPECT_TRUE(meta.ok()) << meta.status().message();
  return *meta;
}

// One received packet of the test stream.
struct Packet {
  bool lidar = false;
  TimeNs receive_ns = 0;
  std::vector<uint8_t> bytes;
};

// IMU packets every 5 ms over [0, 330] ms; frames 0..2 sweeping from 10 ms,
// 100 ms each, each packet received at its last column's time; frame 2 lost
// its second half (the input ends inside it). In receive-time order.
std::vector<Packet> PacketStream(const OusterMetadata& meta) {
  std::vector<Packet> out;
  for (TimeNs t = 0; t <= 330 * kMs; t += 5 * kMs) {
    ImuSample s;
    s.t_ns = t;
    s.acc_imu = Eigen::Vector3d(0.1, -0.2, 9.8);
    s.gyro_imu = Eigen::Vector3d(0.01, 0.02, -0.03);
    out.push_back({false, t, EncodeOusterImuPacket(OusterImuPacketOf(s))});
  }
  const OusterBeamModel beams(meta);
  const int rows = meta.pixels_per_column, cols = meta.columns_per_frame;
  for (uint32_t frame = 0; frame < 3; ++frame) {
    Scan organized;
    organized.points.resize(static_cast<size_t>(rows) * cols);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        LidarPoint& p = organized.points[static_cast<size_t>(r) * cols + c];
        p.p_lidar = beams.PointInSensor(4.0 + 0.05 * c + 0.3 * r, c, r).cast<float>();
        p.intensity = static_cast<float>(10 * r + c % 7);
        p.t_ns = (10 + 100 * static_cast<TimeNs>(frame)) * kMs + c * 100 * kMs / cols;
      }
    std::vector<OusterLidarPacket> packets = OusterPacketsOfScan(meta, organized, frame);
    if (frame == 2) packets.resize(packets.size() / 2);
    for (const OusterLidarPacket& p : packets)
      out.push_back({true, p.columns.back().t_ns, EncodeOusterLidarPacket(meta, p)});
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const Packet& a, const Packet& b) { return a.receive_ns < b.receive_ns; });
  return out;
}

// The packet as a driver's PacketMsg: ROS 1 wire (uint32 length + bytes) or CDR.
std::vector<uint8_t> PacketMessage(WireEncoding encoding, const std::vector<uint8_t>& packet) {
  if (encoding == WireEncoding::kCdr) {
    cdr::Writer w;
    w.Bytes(packet.data(), packet.size());
    return w.Take();
  }
  std::vector<uint8_t> out(4);
  for (int i = 0; i < 4; ++i) out[i] = static_cast<uint8_t>(packet.size() >> (8 * i));
  out.insert(out.end(), packet.begin(), packet.end());
  return out;
}

std::string PacketType(WireEncoding encoding) {
  return encoding == WireEncoding::kRos1 ? "ouster_ros/PacketMsg" : "ouster_sensor_msgs/msg/PacketMsg";
}

LiveSourceOptions PacketOptions(WireEncoding encoding, std::optional<OusterMetadata> meta) {
  LiveSourceOptions o = Options();
  o.encoding = encoding;
  o.lidar.topic = kLidarPackets;
  o.imu.topic = kImuPackets;
  o.ouster = std::move(meta);
  o.ouster_origin = "sensor.json";
  o.live.scan_queue = 8;  // every scan is ready at once when the test drains them
  return o;
}

// What a recording's reader or the live source delivers.
struct Delivered {
  std::vector<Scan> scans;
  std::vector<ImuSample> imu;
  std::string order;  // 'i' per IMU sample, 's' per scan
};

void Take(SensorBagReader* reader, Delivered* out) {
  ImuSample imu;
  Scan scan;
  while (true) {
    StatusOr<SensorMessage> m = reader->Next(&imu, &scan);
    ASSERT_TRUE(m.ok()) << m.status().message();
    if (*m == SensorMessage::kEnd) return;
    out->order += *m == SensorMessage::kImu ? 'i' : 's';
    if (*m == SensorMessage::kImu) out->imu.push_back(imu);
    else out->scans.push_back(scan);
  }
}

void ExpectSameScans(const std::vector<Scan>& want, const std::vector<Scan>& got) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t k = 0; k < want.size(); ++k) {
    EXPECT_EQ(got[k].t_start_ns, want[k].t_start_ns) << "scan " << k;
    EXPECT_EQ(got[k].t_end_ns, want[k].t_end_ns) << "scan " << k;
    ASSERT_EQ(got[k].points.size(), want[k].points.size()) << "scan " << k;
    for (size_t i = 0; i < want[k].points.size(); ++i) {
      ASSERT_EQ(got[k].points[i].p_lidar, want[k].points[i].p_lidar) << "scan " << k << " point " << i;
      ASSERT_EQ(got[k].points[i].t_ns, want[k].points[i].t_ns);
      ASSERT_EQ(got[k].points[i].ring, want[k].points[i].ring);
      ASSERT_EQ(got[k].points[i].intensity, want[k].points[i].intensity);
    }
  }
}

class LiveOusterPackets : public ::testing::TestWithParam<WireEncoding> {};

// The packets of a stream written as the drivers record them (ROS 1 bag,
// ROS 2 MCAP; the metadata on its topic) and read by `run`'s reader give the
// scans and IMU samples that the live source gives for the same packets as
// network messages: every point and sample, the last frame (cut short)
// included, delivered at the stop as at the recording's end.
TEST_P(LiveOusterPackets, GiveTheScansAndSamplesOfTheRecordingsReader) {
  const WireEncoding encoding = GetParam();
  const OusterMetadata meta = SmallSensor();
  const std::vector<Packet> stream = PacketStream(meta);
  const std::string dir = testing_cli::MakeTempDir("rvlio_live_ouster");
  ASSERT_FALSE(dir.empty());
  BagWriterOptions format;
  format.format = encoding == WireEncoding::kRos1 ? "ros1" : "mcap";
  const std::string bag = dir + (encoding == WireEncoding::kRos1 ? "/packets.bag" : "/packets.mcap");
  {
    StatusOr<std::unique_ptr<SensorBagWriter>> writer = SensorBagWriter::Create(bag, format);
    ASSERT_TRUE(writer.ok()) << writer.status().message();
    ASSERT_TRUE((*writer)->WriteString("/ouster/metadata", 0, OusterMetadataJson(meta)).ok());
    for (const Packet& p : stream)
      ASSERT_TRUE((*writer)->WriteOusterPacket(p.lidar ? kLidarPackets : kImuPackets, p.receive_ns,
                                               p.bytes).ok());
    ASSERT_TRUE((*writer)->Close().ok());
  }
  const LiveSourceOptions o = PacketOptions(encoding, meta);
  StatusOr<std::unique_ptr<SensorBagReader>> reader = SensorBagReader::Open(bag, o.lidar, o.imu);
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  Delivered run;
  Take(reader->get(), &run);
  const std::vector<std::string> bag_warnings = (*reader)->warnings();
  std::filesystem::remove_all(dir);

  std::atomic<bool> stop{false};
  LiveSourceOptions live_options = o;
  live_options.stopped = [&stop] { return stop.load(); };
  LiveSensorSource live(live_options);
  const std::string type = PacketType(encoding);
  size_t imu_out = 0;
  for (const Packet& p : stream) {
    const std::vector<uint8_t> m = PacketMessage(encoding, p.bytes);
    if (p.lidar) live.PushLidar(m.data(), m.size(), type, kNow());
    else imu_out += live.PushImu(m.data(), m.size(), type).size();
  }
  stop = true;
  Delivered got;
  Take(&live, &got);
  ASSERT_EQ(run.scans.size(), 3u);
  EXPECT_LT(run.scans[2].points.size(), run.scans[1].points.size());  // half a frame
  ExpectSameScans(run.scans, got.scans);
  EXPECT_EQ(got.order, run.order);
  ASSERT_EQ(got.imu.size(), run.imu.size());
  EXPECT_EQ(imu_out, run.imu.size());  // each sample went to the IMU-rate output too
  for (size_t i = 0; i < run.imu.size(); ++i) {
    EXPECT_EQ(got.imu[i].t_ns, run.imu[i].t_ns);
    EXPECT_EQ(got.imu[i].acc_imu, run.imu[i].acc_imu) << i;  // m/s^2 from the packet's g
    EXPECT_EQ(got.imu[i].gyro_imu, run.imu[i].gyro_imu) << i;
  }
  EXPECT_NEAR(got.imu[0].acc_imu.z(), 9.8, 1e-5);
  EXPECT_EQ(live.lidar_layout(), "ouster_packets");
  // The cut frame's missing columns, counted and said as the bag's reader says them.
  const std::vector<std::string> said = live.warnings();
  ASSERT_EQ(said.size(), 1u);
  const std::string what = ": 1 frames with missing columns (32 columns absent";
  EXPECT_EQ(said[0].find(what), said[0].find(':')) << said[0];
  ASSERT_EQ(bag_warnings.size(), 1u);
  EXPECT_EQ(bag_warnings[0].substr(bag_warnings[0].find(": ")), said[0].substr(said[0].find(": ")));
}

INSTANTIATE_TEST_SUITE_P(Encodings, LiveOusterPackets,
                         ::testing::Values(WireEncoding::kRos1, WireEncoding::kCdr),
                         [](const ::testing::TestParamInfo<WireEncoding>& i) {
                           return i.param == WireEncoding::kRos1 ? std::string("Ros1")
                                                                 : std::string("Ros2");
                         });

// The first error of a packet input, after pushing `stream`'s first packets.
std::string FirstError(LiveSensorSource* s, const std::vector<Packet>& stream) {
  for (size_t k = 0; k < 30 && k < stream.size(); ++k) {
    const std::vector<uint8_t> m = PacketMessage(WireEncoding::kCdr, stream[k].bytes);
    if (stream[k].lidar) s->PushLidar(m.data(), m.size(), PacketType(WireEncoding::kCdr), kNow());
    else s->PushImu(m.data(), m.size(), PacketType(WireEncoding::kCdr));
  }
  return s->error().message();
}

TEST(LiveOusterPackets, WithoutMetadataEndsNamingTheOption) {
  LiveSensorSource s(PacketOptions(WireEncoding::kCdr, std::nullopt));
  EXPECT_EQ(FirstError(&s, PacketStream(SmallSensor())),
            "imu.topic '/ouster/imu_packets' (test) carries Ouster packets "
            "(ouster_sensor_msgs/msg/PacketMsg): give the sensor's metadata JSON with "
            "--ouster-metadata FILE (lidar.ouster_metadata)");
}

// Metadata of another sensor (8 beams for packets of 4): the packet size
// does not match, named with the metadata.
TEST(LiveOusterPackets, MetadataOfAnotherSensorEndsNamingBoth) {
  LiveSensorSource s(PacketOptions(
      WireEncoding::kCdr, SmallSensor({-20.0, -15.0, -10.0, -5.0, 0.0, 5.0, 10.0, 15.0})));
  const std::string err = FirstError(&s, PacketStream(SmallSensor()));
  EXPECT_EQ(err.rfind("lidar.topic '/ouster/lidar_packets' (test) (metadata sensor.json): lidar "
                      "packet of ", 0), 0u) << err;
  EXPECT_NE(err.find("the metadata (64x10, RNG19_RFL8_SIG16_NIR16, 8 beams) gives"),
            std::string::npos) << err;
}

}  // namespace live_ouster

}  // namespace
}  // namespace rvlio

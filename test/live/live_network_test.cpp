// `rvlio live` against real middleware, started and stopped by this test by
// pid: one rosmaster on a free port for every ROS 1 case (rosbag play feeds,
// rosbag record listens), one random DDS domain for the ROS 2 cases (this
// process replays an MCAP recording under ROS 2's conventions through the
// project's DDS transport and subscribes to the odometry). The whole
// executable is one ctest test (Live): the master is started once.
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <nlohmann/json.hpp>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include "dds_transport.h"
#include "rvlio/formats/cdr.h"
#include "rvlio/formats/recording.h"
#include "rvlio/formats/trajectory_io.h"
#include "cli/signals/signals_util.h"

namespace rvlio::live_test {
namespace {

using nlohmann::json;
using signals_test::CompleteLines;
using signals_test::SpawnProgram;
using signals_test::Wait;
using testing_cli::MakeTempDir;
using testing_cli::ReadFile;
using testing_cli::ToolRun;

// Cyclone DDS configuration (CYCLONEDDS_URI accepts the XML itself): the
// loopback interface only, discovery by unicast to the participants of this
// host (participant indexes), no multicast.
constexpr const char* kLoopbackOnlyDds =
    "<CycloneDDS><Domain><General><Interfaces><NetworkInterface address=\"127.0.0.1\"/>"
    "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
    "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20</MaxAutoParticipantIndex>"
    "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>";

constexpr const char* kLidarTopic = "/os_cloud_node/points";
constexpr const char* kImuTopic = "/imu/data";

int FreePort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof(a);
  int port = 0;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0)
    port = ntohs(a.sin_port);
  ::close(fd);
  return port;
}

bool PortOpen(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool open = ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
  ::close(fd);
  return open;
}

// The shared rosmaster, DDS domain and simulated recordings.
struct World {
  std::string dir;
  pid_t master = -1;
  int domain = 0;
  std::string bag, mcap, config;
  std::string run_dir;  // `rvlio run` on the recording: what live must reproduce
};
World* world = nullptr;

class LiveEnvironment : public ::testing::Environment {
 public:
  void SetUp() override {
    world = new World;
    world->dir = MakeTempDir("rvlio_live");
    ASSERT_FALSE(world->dir.empty());
    ::setenv("ROS_HOME", (world->dir + "/ros").c_str(), 1);  // rosmaster's and roscpp's logs
    const int port = FreePort();
    ASSERT_GT(port, 0);
    world->master = SpawnProgram({"rosmaster", "--core", "-p", std::to_string(port)},
                                 world->dir + "/master.out", world->dir + "/master.err", true);
    for (int i = 0; i < 200 && !PortOpen(port); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ASSERT_TRUE(PortOpen(port)) << ReadFile(world->dir + "/master.err");
    ::setenv("ROS_MASTER_URI", ("http://127.0.0.1:" + std::to_string(port)).c_str(), 1);
    // Every process stays on the loopback interface: roscpp's URIs, and DDS
    // discovery by unicast to 127.0.0.1 (no multicast onto another interface).
    ::setenv("ROS_IP", "127.0.0.1", 1);
    ::setenv("CYCLONEDDS_URI", kLoopbackOnlyDds, 1);
    std::random_device rd;
    world->domain = 1 + static_cast<int>(rd() % 200);  // no cross-talk with other runs
    ::setenv("ROS_DOMAIN_ID", std::to_string(world->domain).c_str(), 1);
    const ToolRun bag = testing_cli::SimulateTunnel(world->dir + "/data", 4, 6, world->dir);
    ASSERT_EQ(bag.exit_code, 0) << bag.err;
    const ToolRun mcap =
        testing_cli::SimulateTunnel(world->dir + "/mcap", 4, 6, world->dir, "--format mcap");
    ASSERT_EQ(mcap.exit_code, 0) << mcap.err;
    world->bag = world->dir + "/data/tunnel.bag";
    world->mcap = world->dir + "/mcap/tunnel.mcap";
    world->config = world->dir + "/data/tunnel.yaml";
    world->run_dir = world->dir + "/run";
    const ToolRun run = testing_cli::RunTool(
        "run --quiet --bag " + world->bag + " --config " + world->config + " --out " + world->run_dir,
        world->dir);
    ASSERT_EQ(run.exit_code, 0) << run.err;
  }
  void TearDown() override {
    if (world->master > 0) {
      ::kill(-world->master, SIGTERM);
      Wait(world->master);
    }
    std::filesystem::remove_all(world->dir);
    delete world;
  }
};
::testing::Environment* const kEnvironment =
    ::testing::AddGlobalTestEnvironment(new LiveEnvironment);

// `rvlio live` as a child; WaitReady() once it subscribed.
struct LiveProcess {
  std::string out, log;
  pid_t pid = -1;
  LiveProcess(const std::string& name, const std::vector<std::string>& extra,
              const std::string& config = world->config) {
    out = world->dir + "/" + name;
    log = world->dir + "/" + name + ".log";
    std::vector<std::string> args = {"live", "--config", config, "--out", out};
    args.insert(args.end(), extra.begin(), extra.end());
    pid = signals_test::Spawn(args, log + ".out", log);
  }
  // Subscribed: RunRecording has started (it opens trajectory.partial.tum).
  bool WaitReady() const {
    int status = 0;
    return signals_test::WaitUntil(
        pid, [&] { return std::filesystem::exists(out + "/trajectory.partial.tum"); }, &status);
  }
  int Stop(int signal = SIGINT) const {
    ::kill(pid, signal);
    return Wait(pid);
  }
  std::string Err() const { return ReadFile(log); }
  json Summary() const { return json::parse(ReadFile(out + "/summary.json"), nullptr, false); }
};

Trajectory ReadTrajectory(const std::string& path) {
  StatusOr<Trajectory> t = ReadTum(path);
  EXPECT_TRUE(t.ok()) << t.status().message();
  return t.ok() ? *t : Trajectory();
}

// The poses of `got` equal those of `want` (stamps exactly, poses to 1e-6).
void ExpectSamePoses(const Trajectory& want, const Trajectory& got) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) {
    ASSERT_EQ(got[i].t_ns, want[i].t_ns) << "pose " << i;
    ASSERT_LT((got[i].p_world_imu - want[i].p_world_imu).norm(), 1e-6) << "pose " << i;
    ASSERT_LT(got[i].q_world_imu.angularDistance(want[i].q_world_imu), 1e-6) << "pose " << i;
  }
}

// Complete outputs of a live run: run's four files, summary.json with "live".
void ExpectCompleteOutputs(const LiveProcess& live) {
  for (const char* f : {"trajectory.tum", "map.pcd", "scans.csv", "summary.json"})
    EXPECT_TRUE(std::filesystem::exists(live.out + "/" + f)) << f << "\n" << live.Err();
  EXPECT_FALSE(std::filesystem::exists(live.out + "/trajectory.partial.tum"));
  const json s = live.Summary();
  ASSERT_TRUE(s.is_object()) << live.Err();
  EXPECT_EQ(s["command"], "live");
  EXPECT_EQ(s["interrupted"], true);
  EXPECT_TRUE(s["live"].is_object());
  EXPECT_EQ(CompleteLines(ReadFile(live.out + "/scans.csv")).size(),
            ReadTrajectory(live.out + "/trajectory.tum").size() + 1);
}

// rosbag play of a recording (the simulated one) at `rate`, after 1 s for
// the subscribers to connect; returns its exit status.
int Play(double rate, const std::string& bag = world->bag) {
  const pid_t play = SpawnProgram({"rosbag", "play", "-q", "-d", "1", "-r", std::to_string(rate), bag},
                                  world->dir + "/play.out", world->dir + "/play.err", true);
  return Wait(play);
}

// One line on stderr starting "rvlio live: error: " and holding `what`.
void ExpectOneLiveErrorLine(const std::string& err, const std::string& what) {
  EXPECT_EQ(err.rfind("rvlio live: error: ", 0), 0u) << err;
  EXPECT_NE(err.find(what), std::string::npos) << err;
  EXPECT_EQ(err.find('\n'), err.size() - 1) << "more than one line: " << err;
}

// ---------------------------------------------------------------------------
// ROS 1
// ---------------------------------------------------------------------------

TEST(LiveRos1, PublishesRunsEstimateTfAndCloud) {
  const std::string recorded = world->dir + "/published.bag";
  // rosbag record is a Python program that runs the recorder as its child:
  // its own process group, so that SIGINT reaches the recorder, which then
  // closes the bag.
  const pid_t record = SpawnProgram(
      {"rosbag", "record", "-O", recorded, "/rvlio/odometry", "/tf", "/rvlio/cloud_registered",
       "/rvlio/odometry_imu", "/rvlio/status"},
      world->dir + "/record.out", world->dir + "/record.err", /*own_group=*/true);
  LiveProcess live("ros1", {"--ros1"});
  ASSERT_TRUE(live.WaitReady()) << live.Err();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // record connects to live
  ASSERT_EQ(Play(1.0), 0) << ReadFile(world->dir + "/play.err");
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // the last scans are estimated
  EXPECT_EQ(live.Stop(SIGINT), 0) << live.Err();
  ::kill(-record, SIGINT);
  Wait(record);
  for (int i = 0; i < 200 && (std::filesystem::exists(recorded + ".active") ||
                              !std::filesystem::exists(recorded));
       ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_TRUE(std::filesystem::exists(recorded)) << ReadFile(world->dir + "/record.err");
  ExpectCompleteOutputs(live);
  const Trajectory run = ReadTrajectory(world->run_dir + "/trajectory.tum");
  ExpectSamePoses(run, ReadTrajectory(live.out + "/trajectory.tum"));
  EXPECT_EQ(live.Summary()["live"]["scans_dropped"], 0);

  // What rosbag record received.
  rosbag::Bag bag(recorded, rosbag::bagmode::Read);
  Trajectory odometry, imu_odometry;
  int tf = 0, clouds = 0, imu_rate = 0;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (m.getTopic() == "/rvlio/odometry") {
      const auto o = m.instantiate<nav_msgs::Odometry>();
      EXPECT_EQ(o->header.frame_id, "odom");
      EXPECT_EQ(o->child_frame_id, "base");
      StampedPose p;
      p.t_ns = static_cast<TimeNs>(o->header.stamp.toNSec());
      p.p_world_imu = {o->pose.pose.position.x, o->pose.pose.position.y, o->pose.pose.position.z};
      p.q_world_imu = Eigen::Quaterniond(o->pose.pose.orientation.w, o->pose.pose.orientation.x,
                                         o->pose.pose.orientation.y, o->pose.pose.orientation.z);
      odometry.push_back(p);
      EXPECT_GT(o->pose.covariance[0], 0.0);  // the IESKF's posterior
    } else if (m.getTopic() == "/tf") {
      const auto t = m.instantiate<tf2_msgs::TFMessage>();
      ASSERT_EQ(t->transforms.size(), 1u);
      EXPECT_EQ(t->transforms[0].header.frame_id, "odom");
      EXPECT_EQ(t->transforms[0].child_frame_id, "base");
      ++tf;
    } else if (m.getTopic() == "/rvlio/cloud_registered") {
      const auto c = m.instantiate<sensor_msgs::PointCloud2>();
      EXPECT_EQ(c->header.frame_id, "odom");
      EXPECT_GT(c->width, 1000u);
      ++clouds;
    } else if (m.getTopic() == "/rvlio/odometry_imu") {
      const auto o = m.instantiate<nav_msgs::Odometry>();
      StampedPose p;
      p.t_ns = static_cast<TimeNs>(o->header.stamp.toNSec());
      p.p_world_imu = {o->pose.pose.position.x, o->pose.pose.position.y, o->pose.pose.position.z};
      imu_odometry.push_back(p);
      ++imu_rate;
    }
  }
  // The IMU-rate pose next to each scan end (propagated from the previous
  // estimate) is within what one update moves the pose of the estimate.
  int compared = 0;
  for (size_t k = 1; k < run.size(); ++k) {
    const StampedPose* near = nullptr;
    for (const StampedPose& p : imu_odometry)
      if (p.t_ns <= run[k].t_ns && p.t_ns > run[k - 1].t_ns) near = &p;
    if (near == nullptr || run[k].t_ns - near->t_ns > 10000000) continue;
    EXPECT_LT((near->p_world_imu - run[k].p_world_imu).norm(), 0.05) << "scan " << k;
    ++compared;
  }
  EXPECT_GT(compared, static_cast<int>(run.size()) / 2);
  ExpectSamePoses(run, odometry);
  EXPECT_EQ(tf, static_cast<int>(run.size()));
  EXPECT_GE(clouds, static_cast<int>(run.size()) - 1);  // the first scan has no IMU before it
  EXPECT_GT(imu_rate, 5 * static_cast<int>(run.size()));
  const json latency = live.Summary()["live"]["latency_ms"];
  EXPECT_EQ(latency["samples"], run.size());
  std::printf("ros1 1x: latency median %.2f ms p95 %.2f ms (IMU wait median %.2f ms; after the "
              "IMU median %.2f p95 %.2f ms), per scan median %.2f ms\n",
              latency["median"].get<double>(), latency["p95"].get<double>(),
              latency["imu_wait_median"].get<double>(), latency["after_imu_median"].get<double>(),
              latency["after_imu_p95"].get<double>(),
              live.Summary()["per_scan_ms"]["median"].get<double>());
}

// SIGINT while scans arrive: complete outputs, the scans received are run's
// first scans.
TEST(LiveRos1, SigintMidRunWritesRunsPrefix) {
  LiveProcess live("ros1_sigint", {"--ros1"});
  ASSERT_TRUE(live.WaitReady()) << live.Err();
  // rosbag play runs the player as its child: a process group of its own.
  const pid_t play = SpawnProgram({"rosbag", "play", "-q", "-d", "1", world->bag},
                                  world->dir + "/play2.out", world->dir + "/play2.err", true);
  int status = 0;
  ASSERT_TRUE(signals_test::WaitUntil(  // about a third of the flight estimated
      live.pid, [&] { return signals_test::CountLines(live.out + "/trajectory.partial.tum") >= 16; },
      &status)) << status << live.Err();
  EXPECT_EQ(live.Stop(SIGINT), 0) << live.Err();
  ::kill(-play, SIGINT);
  Wait(play);
  ExpectCompleteOutputs(live);
  const Trajectory run = ReadTrajectory(world->run_dir + "/trajectory.tum");
  Trajectory part = ReadTrajectory(live.out + "/trajectory.tum");
  ASSERT_GT(part.size(), 3u);
  ASSERT_LT(part.size(), run.size());
  // The last scan received may have been finished at the stop with the IMU
  // there was (as run finishes a recording's last scans): the ones before it
  // are run's, pose for pose; the last one's stamp is run's.
  const long n = static_cast<long>(part.size()) - 1;
  EXPECT_EQ(part.back().t_ns, run[static_cast<size_t>(n)].t_ns);
  part.pop_back();
  ExpectSamePoses(Trajectory(run.begin(), run.begin() + n), part);
  EXPECT_EQ(live.Summary()["signal"], "SIGINT");
  EXPECT_NEAR(live.Summary()["last_stamp_s"].get<double>(),
              NsToSeconds(ReadTrajectory(live.out + "/trajectory.tum").back().t_ns), 1e-9);
}

// The player at 20x: scans are dropped and counted, the IMU-rate output
// keeps the IMU's rate, SIGTERM writes valid outputs.
TEST(LiveRos1, FallingBehindDropsScansNotImu) {
  // A finer voxel grid: about 10 ms a scan, twice the 5 ms between scans at
  // 20x, so the estimator falls behind whatever the machine's load.
  LiveProcess live("ros1_20x", {"--ros1", "--set", "lidar.voxel_size=0.05"});
  ASSERT_TRUE(live.WaitReady()) << live.Err();
  ASSERT_EQ(Play(20.0), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_EQ(live.Stop(SIGTERM), 0) << live.Err();
  ExpectCompleteOutputs(live);
  const json l = live.Summary()["live"];
  EXPECT_GT(l["scans_dropped"].get<int>(), 0) << l;
  EXPECT_EQ(l["imu_dropped"], 0) << l;
  EXPECT_GE(l["imu_odometry_hz"].get<double>(), 0.8 * l["imu_input_hz"].get<double>()) << l;
  EXPECT_EQ(live.Summary()["signal"], "SIGTERM");
  EXPECT_GT(ReadTrajectory(live.out + "/trajectory.tum").size(), 3u);
}

// Ouster packets (`simulate --format ouster-bag`: the ROS driver's packet
// topics in a ROS 1 bag) played by rosbag: `live --ouster-metadata` gives
// `run`'s poses on that bag; without the metadata, or with another sensor's,
// it stops at the first packet with one line, exit 2.
TEST(LiveRos1, OusterPacketsGiveRunsEstimate) {
  const std::string dir = world->dir + "/ouster";
  const ToolRun sim = testing_cli::SimulateTunnel(dir, 4, 6, world->dir, "--format ouster-bag");
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const std::string bag = dir + "/tunnel.bag", config = dir + "/tunnel.yaml";
  const std::string json = dir + "/tunnel.json";
  const ToolRun run = testing_cli::RunTool(
      "run --quiet --bag " + bag + " --config " + config + " --out " + world->dir + "/run_ouster",
      world->dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  LiveProcess live("ros1_ouster", {"--ros1", "--ouster-metadata", json}, config);
  LiveProcess no_metadata("ros1_ouster_nometa", {"--ros1"}, config);
  const std::string other = std::string(RVLIO_TEST_DATA) + "/ouster/OS-1-32-G_v2.1.1_1024x10.json";
  LiveProcess other_sensor("ros1_ouster_other", {"--ros1", "--ouster-metadata", other}, config);
  for (const LiveProcess* p : {&live, &no_metadata, &other_sensor})
    ASSERT_TRUE(p->WaitReady()) << p->Err();
  ASSERT_EQ(Play(1.0, bag), 0) << ReadFile(world->dir + "/play.err");
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // the last scans are estimated
  EXPECT_EQ(live.Stop(SIGINT), 0) << live.Err();
  ExpectCompleteOutputs(live);
  const Trajectory want = ReadTrajectory(world->dir + "/run_ouster/trajectory.tum");
  ASSERT_GT(want.size(), 40u);
  ExpectSamePoses(want, ReadTrajectory(live.out + "/trajectory.tum"));
  EXPECT_EQ(live.Summary()["live"]["scans_dropped"], 0);
  EXPECT_EQ(live.Summary()["lidar_layout"], "ouster_packets") << live.Summary().dump();

  EXPECT_EQ(Wait(no_metadata.pid), 2);
  ExpectOneLiveErrorLine(no_metadata.Err(),
                         "carries Ouster packets (ouster_ros/PacketMsg): give the sensor's "
                         "metadata JSON with --ouster-metadata FILE");
  EXPECT_EQ(Wait(other_sensor.pid), 2);
  ExpectOneLiveErrorLine(other_sensor.Err(), "lidar.topic '/ouster/lidar_packets' (ROS 1 master ");
  EXPECT_NE(other_sensor.Err().find(other + "): lidar packet of "), std::string::npos)
      << other_sensor.Err();
  for (const LiveProcess* p : {&no_metadata, &other_sensor})
    EXPECT_FALSE(std::filesystem::exists(p->out + "/summary.json"));
}

TEST(LiveRos1, WrongTopicTypeIsOneLine) {
  LiveProcess live("ros1_type", {"--ros1", "--set", std::string("lidar.topic=") + kImuTopic});
  ASSERT_TRUE(live.WaitReady()) << live.Err();
  const pid_t play = SpawnProgram({"rosbag", "play", "-q", "-d", "1", world->bag},
                                  world->dir + "/play3.out", world->dir + "/play3.err", true);
  const int rc = Wait(live.pid);
  ::kill(-play, SIGINT);
  Wait(play);
  EXPECT_EQ(rc, 2);
  const std::string err = live.Err();
  EXPECT_EQ(err.rfind("rvlio live: error: ", 0), 0u) << err;
  EXPECT_NE(err.find("carries sensor_msgs/Imu, expected sensor_msgs/PointCloud2"),
            std::string::npos) << err;
  EXPECT_EQ(err.find('\n'), err.size() - 1) << "more than one line: " << err;
  EXPECT_FALSE(std::filesystem::exists(live.out + "/summary.json"));
}

TEST(LiveRos1, NoPublisherIsOneLineNamingTheTopic) {
  LiveProcess live("ros1_silent", {"--ros1", "--set", "lidar.wait_timeout=1"});
  EXPECT_EQ(Wait(live.pid), 2);
  const std::string err = live.Err();
  EXPECT_EQ(err.rfind("rvlio live: error: no message on lidar.topic '/os_cloud_node/points' "
                      "within lidar.wait_timeout 1.0 s", 0), 0u) << err;
  EXPECT_EQ(err.find('\n'), err.size() - 1) << "more than one line: " << err;
  EXPECT_FALSE(std::filesystem::exists(live.out)) << "an output folder was left";
}

TEST(LiveRos1, UnreachableMasterIsOneLine) {
  const int port = FreePort();
  const std::string cmd = "ROS_MASTER_URI=http://127.0.0.1:" + std::to_string(port) + " " +
                          RVLIO_BIN + " live --ros1 --set live.connect_timeout=0.5 --out " +
                          world->dir + "/nomaster";
  const ToolRun r = testing_cli::RunTool("", world->dir, cmd);
  testing_cli::ExpectOneErrorLine(r, "live", "did not answer within live.connect_timeout 0.5 s");
  EXPECT_FALSE(std::filesystem::exists(world->dir + "/nomaster"));
  const ToolRun unset = testing_cli::RunTool("", world->dir, "env -u ROS_MASTER_URI " +
                                                                 std::string(RVLIO_BIN) +
                                                                 " live --ros1 --out " +
                                                                 world->dir + "/nomaster");
  testing_cli::ExpectOneErrorLine(unset, "live", "ROS_MASTER_URI is not set");
  // Metadata that cannot be read is refused before connecting.
  const ToolRun no_file = testing_cli::RunTool(
      "live --ros1 --ouster-metadata " + world->dir + "/missing.json --out " + world->dir + "/nomaster",
      world->dir);
  testing_cli::ExpectOneErrorLine(no_file, "live",
                                  "cannot read Ouster metadata '" + world->dir + "/missing.json'");
  EXPECT_FALSE(std::filesystem::exists(world->dir + "/nomaster"));
}

// ---------------------------------------------------------------------------
// ROS 2 on DDS
// ---------------------------------------------------------------------------

// The MCAP recording published under ROS 2's names (reliable, so that no
// fragment of a large cloud is lost on a busy host), paced by its receive
// times at `rate`.
void PlayMcap(live_detail::DdsTransport* dds, double rate, const std::string& lidar_as) {
  StatusOr<std::unique_ptr<RecordingSource>> source = RecordingSource::Open(world->mcap);
  ASSERT_TRUE(source.ok()) << source.status().message();
  std::vector<std::string> names;
  for (const RecordingTopic& t : (*source)->topics()) {
    const std::string name = t.name == kLidarTopic ? lidar_as : t.name;
    names.push_back(name);
    ASSERT_TRUE(dds->AdvertiseRaw(name, t.type, true).ok());
  }
  for (int i = 0; i < 200 && (dds->MatchedReaders(lidar_as) < 1 || dds->MatchedReaders(kImuTopic) < 1); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  ASSERT_GE(dds->MatchedReaders(kImuTopic), 1);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  RawMessage m;
  TimeNs first_ns = -1;
  const auto t0 = std::chrono::steady_clock::now();
  while (*(*source)->Next(&m)) {
    if (first_ns < 0) first_ns = m.stamp_ns;
    std::this_thread::sleep_until(
        t0 + std::chrono::nanoseconds(static_cast<TimeNs>((m.stamp_ns - first_ns) / rate)));
    dds->PublishRaw(names[m.topic], m.data);
  }
}

TEST(LiveRos2, PublishesRunsEstimate) {
  live_detail::DdsTransport dds;
  ASSERT_TRUE(dds.Init(world->domain).ok());
  std::mutex mutex;
  Trajectory odometry;
  int tf = 0;
  ASSERT_TRUE(dds.Subscribe("/rvlio/odometry", 100,
                            [&](const uint8_t* data, size_t size, const std::string& type) {
                              EXPECT_EQ(type, cdr::kOdometryType);
                              StatusOr<OdometryMessage> o = cdr::DecodeOdometry(data, size, "");
                              ASSERT_TRUE(o.ok()) << o.status().message();
                              StampedPose p;
                              p.t_ns = o->stamp_ns;
                              const auto& q = o->pose.orientation_xyzw;
                              p.p_world_imu = Eigen::Vector3d(o->pose.position.data());
                              p.q_world_imu = Eigen::Quaterniond(q[3], q[0], q[1], q[2]);
                              std::lock_guard<std::mutex> lock(mutex);
                              odometry.push_back(p);
                            })
                  .ok());
  ASSERT_TRUE(dds.Subscribe("/tf", 100, [&](const uint8_t* data, size_t size, const std::string&) {
                   StatusOr<std::vector<TransformMessage>> t = cdr::DecodeTfMessage(data, size, "");
                   ASSERT_TRUE(t.ok());
                   std::lock_guard<std::mutex> lock(mutex);
                   tf += static_cast<int>(t->size());
                 }).ok());
  LiveProcess live("ros2", {"--ros2", "--domain-id", std::to_string(world->domain)});
  ASSERT_TRUE(live.WaitReady()) << live.Err();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // the subscriptions match
  PlayMcap(&dds, 1.0, kLidarTopic);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_EQ(live.Stop(SIGINT), 0) << live.Err();
  dds.Shutdown();
  ExpectCompleteOutputs(live);
  const Trajectory run = ReadTrajectory(world->run_dir + "/trajectory.tum");
  ExpectSamePoses(run, ReadTrajectory(live.out + "/trajectory.tum"));
  std::lock_guard<std::mutex> lock(mutex);
  ExpectSamePoses(run, odometry);
  EXPECT_EQ(tf, static_cast<int>(run.size()));
  const json l = live.Summary()["live"];
  EXPECT_EQ(l["middleware"], "ros2");
  EXPECT_EQ(l["scans_dropped"], 0);
  std::printf("ros2 1x: latency median %.2f ms p95 %.2f ms, IMU-rate odometry %.1f Hz of %.1f Hz, "
              "per scan median %.2f ms\n",
              l["latency_ms"]["median"].get<double>(), l["latency_ms"]["p95"].get<double>(),
              l["imu_odometry_hz"].get<double>(), l["imu_input_hz"].get<double>(),
              live.Summary()["per_scan_ms"]["median"].get<double>());
}

TEST(LiveRos2, WrongTopicTypeIsOneLine) {
  live_detail::DdsTransport dds;
  ASSERT_TRUE(dds.Init(world->domain).ok());
  LiveProcess live("ros2_type", {"--ros2", "--set", "lidar.topic=/scan_as_string"});
  ASSERT_TRUE(live.WaitReady()) << live.Err();
  ASSERT_TRUE(dds.AdvertiseRaw("/scan_as_string", cdr::kStringType, true).ok());
  ASSERT_TRUE(dds.AdvertiseRaw(kImuTopic, cdr::kImuType, true).ok());
  int status = 0;
  signals_test::WaitUntil(live.pid, [&] {
    dds.PublishRaw("/scan_as_string", cdr::EncodeString("not a cloud"));
    return false;
  }, &status);
  EXPECT_EQ(status, 2);
  EXPECT_NE(live.Err().find("rvlio live: error: lidar.topic '/scan_as_string' (ROS 2 on DDS, domain " +
                            std::to_string(world->domain) + ") carries std_msgs/msg/String"),
            std::string::npos) << live.Err();
}

// A cloud whose bytes end early: the CDR decoder's one line, exit 2.
TEST(LiveRos2, CorruptCloudIsOneLine) {
  live_detail::DdsTransport dds;
  ASSERT_TRUE(dds.Init(world->domain).ok());
  LiveProcess live("ros2_corrupt", {"--ros2", "--set", "lidar.topic=/cut_cloud"});
  ASSERT_TRUE(live.WaitReady()) << live.Err();
  ASSERT_TRUE(dds.AdvertiseRaw("/cut_cloud", cdr::kPointCloud2Type, true).ok());
  std::vector<uint8_t> cut = cdr::EncodeString("0123456789abcdef");  // a header, then too little
  int status = 0;
  signals_test::WaitUntil(live.pid, [&] {
    dds.PublishRaw("/cut_cloud", cut);
    return false;
  }, &status);
  EXPECT_EQ(status, 2);
  const std::string err = live.Err();
  EXPECT_NE(err.find("rvlio live: error: CDR sensor_msgs/msg/PointCloud2 on /cut_cloud"), std::string::npos)
      << err;
  EXPECT_NE(err.find("(ROS 2 on DDS, domain"), std::string::npos) << err;
}

}  // namespace
}  // namespace rvlio::live_test

// End-to-end input paths on a short simulated tunnel (10 s, 512 columns):
// Livox CustomMsg vs PointCloud2, lidar.time_offset, --start / --duration,
// and the reader thread (OpenSensorStream) against inline reading.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_util.h"
#include "rvlio/formats/sensor_stream.h"
#include "rvlio/formats/trajectory_io.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;
using testing_cli::EvalJson;
using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

constexpr double kInjectedOffsetS = 0.03;

class InputStreamTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing_cli::MakeTempDir("rvlio_input");
    ASSERT_FALSE(dir_.empty());
    for (const std::string& extra :
         {std::string("--name pc"), std::string("--name lx --lidar-msg livox"),
          std::string("--name lxm --lidar-msg livox --format mcap"),
          "--name off --set lidar.time_offset=" + std::to_string(kInjectedOffsetS)}) {
      const ToolRun sim = testing_cli::SimulateTunnel(dir_, 4, 10, dir_, extra);
      ASSERT_EQ(sim.exit_code, 0) << sim.err;
    }
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static std::string Data(const std::string& name) { return dir_ + "/" + name; }
  // `rvlio run NAME.bag --config NAME.yaml --out dir_/OUT ARGS`.
  static ToolRun Run(const std::string& name, const std::string& out, const std::string& args = "") {
    const std::string bag = Data(name + (fs::exists(Data(name + ".mcap")) ? ".mcap" : ".bag"));
    return RunTool("run --quiet --bag " + bag + " --config " +
                       Data(name + ".yaml") + " --out " + Data(out) + " " + args,
                   dir_);
  }
  static double Ate(const std::string& out) {
    const nlohmann::json j = EvalJson(Data("pc_gt.tum"), Data(out + "/trajectory.tum"), dir_);
    if (!j.is_object()) return NAN;
    return j["ape"]["rmse"].get<double>();
  }

  static std::string dir_;
};
std::string InputStreamTest::dir_;

// The simulator writes the same scans either way; CustomMsg carries the same
// coordinates and times (offset_time in ns), so the runs agree to the byte,
// from a ROS1 bag (livox_ros_driver/CustomMsg) and from a ROS 2 MCAP file
// (livox_ros_driver2/msg/CustomMsg). Only the intensity differs (uint8
// reflectivity), which the estimator does not use.
TEST_F(InputStreamTest, LivoxCustomMsgGivesThePointCloud2Trajectory) {
  EXPECT_NE(ReadFile(Data("lx.yaml")).find("topic: /livox/lidar"), std::string::npos);
  const ToolRun pc = Run("pc", "pc_out");
  ASSERT_EQ(pc.exit_code, 0) << pc.err;
  const ToolRun lx = Run("lx", "lx_out");
  ASSERT_EQ(lx.exit_code, 0) << lx.err;
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(Data("lx_out/summary.json")));
  EXPECT_NE(summary.dump().find("livox_custom"), std::string::npos);
  StatusOr<Trajectory> a = ReadTum(Data("pc_out/trajectory.tum"));
  StatusOr<Trajectory> b = ReadTum(Data("lx_out/trajectory.tum"));
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->size(), b->size());
  for (size_t i = 0; i < a->size(); ++i) {
    EXPECT_EQ((*a)[i].t_ns, (*b)[i].t_ns);
    EXPECT_LT(((*a)[i].p_world_imu - (*b)[i].p_world_imu).norm(), 1e-6) << i;
  }
  EXPECT_LT(Ate("lx_out"), 0.05);
  const ToolRun lxm = Run("lxm", "lxm_out");
  ASSERT_EQ(lxm.exit_code, 0) << lxm.err;
  EXPECT_TRUE(ReadFile(Data("lxm_out/trajectory.tum")) == ReadFile(Data("lx_out/trajectory.tum")));
}

// Stamps written 30 ms early: uncorrected the ATE grows; lidar.time_offset
// = 0.03 brings it back within 10 % of the synchronized run.
TEST_F(InputStreamTest, TimeOffsetUndoesAnInjectedLidarDelay) {
  ASSERT_EQ(Run("pc", "sync_out").exit_code, 0);
  // Uncorrected, the divergence monitor may flag the run (exit 3); the
  // trajectory is what is measured here.
  const ToolRun raw_run = Run("off", "raw_out", "--allow-divergence");
  ASSERT_EQ(raw_run.exit_code, 0) << raw_run.err;
  const ToolRun fixed =
      Run("off", "fixed_out", "--set lidar.time_offset=" + std::to_string(kInjectedOffsetS));
  ASSERT_EQ(fixed.exit_code, 0) << fixed.err;
  const double sync = Ate("sync_out"), raw = Ate("raw_out"), corrected = Ate("fixed_out");
  EXPECT_GT(raw, 1.5 * sync) << "sync " << sync << " raw " << raw;
  EXPECT_LT(std::abs(corrected - sync), 0.1 * sync) << "sync " << sync << " fixed " << corrected;
}

TEST_F(InputStreamTest, StartAndDurationSelectTheScansOfTheWindow) {
  const ToolRun r = Run("pc", "win_out", "--start 3 --duration 4");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  StatusOr<Trajectory> traj = ReadTum(Data("win_out/trajectory.tum"));
  StatusOr<Trajectory> truth = ReadTum(Data("pc_gt.tum"));
  ASSERT_TRUE(traj.ok() && truth.ok() && !traj->empty());
  // The first message of the recording is the first IMU sample, at the
  // ground truth's first stamp.
  const double t0 = NsToSeconds(truth->front().t_ns);
  const double first = NsToSeconds(traj->front().t_ns) - t0;
  const double last = NsToSeconds(traj->back().t_ns) - t0;
  EXPECT_GE(first, 3.0);
  EXPECT_LT(first, 3.3);  // within a few scans (10 Hz) of the start
  EXPECT_LE(last, 7.0);
  EXPECT_GT(last, 6.8);
}

TEST_F(InputStreamTest, StartPastTheEndIsOneLineExitTwo) {
  const ToolRun r = Run("pc", "past_out", "--start 12.5");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "rvlio run: error: recording '" + Data("pc.bag") +
                       "' is 10.000 s long; --start 12.500 s is at or past its end\n");
  EXPECT_FALSE(fs::exists(Data("past_out")));
  const ToolRun bad = Run("pc", "past_out", "--duration -1");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--duration '-1'"), std::string::npos) << bad.err;
}

// scans.csv without its timing and memory columns (ms, rss_mb).
std::string DeterministicColumns(const std::string& csv) {
  std::istringstream in(csv);
  std::string line, out;
  std::vector<bool> keep;
  while (std::getline(in, line)) {
    std::istringstream cells(line);
    std::string cell;
    for (size_t i = 0; std::getline(cells, cell, ','); ++i) {
      if (keep.size() <= i) keep.push_back(cell != "ms" && cell != "rss_mb");
      if (keep[i]) out += cell + ",";
    }
    out += "\n";
  }
  return out;
}

TEST_F(InputStreamTest, ReaderThreadOutputsAreByteIdentical) {
  ASSERT_EQ(Run("pc", "thread_out", "--set io.reader_thread=true --set io.queue_messages=3")
                .exit_code, 0);
  ASSERT_EQ(Run("pc", "inline_out", "--set io.reader_thread=false").exit_code, 0);
  for (const char* file : {"trajectory.tum", "map.pcd"}) {
    const std::string a = ReadFile(Data(std::string("thread_out/") + file));
    ASSERT_FALSE(a.empty()) << file;
    EXPECT_TRUE(a == ReadFile(Data(std::string("inline_out/") + file))) << file;
  }
  const std::string scans = DeterministicColumns(ReadFile(Data("thread_out/scans.csv")));
  EXPECT_GT(std::count(scans.begin(), scans.end(), '\n'), 50);
  EXPECT_EQ(scans, DeterministicColumns(ReadFile(Data("inline_out/scans.csv"))));
}

// A chunk damaged midway: the thread delivers every message before it, then
// the error; the run writes the same outputs and says the same as inline.
TEST_F(InputStreamTest, ReaderErrorMidwayBehavesAsInline) {
  std::string bytes = ReadFile(Data("pc.bag"));
  const std::string chunk_header = std::string("compression=none", 16);
  size_t at = 0;
  for (int k = 0; k < 25; ++k) at = bytes.find(chunk_header, at + 1);
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at, chunk_header.size(), "compression=zzzz");
  const std::string bad = Data("corrupt.bag");
  std::ofstream(bad, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  const std::string config = " --config " + Data("pc.yaml");
  const ToolRun threaded = RunTool("run --quiet --bag " + bad + config + " --out " +
                                       Data("bad_thread") + " --set io.reader_thread=true", dir_);
  const ToolRun inline_run = RunTool("run --quiet --bag " + bad + config + " --out " +
                                         Data("bad_inline") + " --set io.reader_thread=false", dir_);
  EXPECT_EQ(threaded.exit_code, 2);
  EXPECT_EQ(inline_run.exit_code, 2);
  EXPECT_NE(threaded.err.find("(outputs hold the scans read before it)"), std::string::npos)
      << threaded.err;
  EXPECT_EQ(threaded.err, inline_run.err);
  const std::string traj = ReadFile(Data("bad_thread/trajectory.tum"));
  EXPECT_FALSE(traj.empty());
  EXPECT_TRUE(traj == ReadFile(Data("bad_inline/trajectory.tum")));
  EXPECT_TRUE(ReadFile(Data("bad_thread/map.pcd")) == ReadFile(Data("bad_inline/map.pcd")));
}

// Everything the stream delivers, with the stats after each message.
struct Delivered {
  std::vector<TimeNs> stamps;
  std::vector<int64_t> scans_so_far;
  Status error;
};

Delivered ReadAll(SensorBagReader* reader, int max_messages = -1) {
  Delivered d;
  ImuSample imu;
  Scan scan;
  for (int i = 0; max_messages < 0 || i < max_messages; ++i) {
    StatusOr<SensorMessage> m = reader->Next(&imu, &scan);
    if (!m.ok()) {
      d.error = m.status();
      break;
    }
    if (*m == SensorMessage::kEnd) break;
    d.stamps.push_back(*m == SensorMessage::kImu ? imu.t_ns : scan.t_end_ns);
    d.scans_so_far.push_back(reader->stats().scans);
  }
  return d;
}

TEST_F(InputStreamTest, StreamThreadDeliversWhatInlineDeliversAndStopsEarlyCleanly) {
  LidarOptions lidar;
  lidar.type = "ouster";
  ImuOptions imu;
  ReaderOptions inline_io, thread_io;
  inline_io.reader_thread = false;
  thread_io.queue_messages = 2;
  auto a = OpenSensorStream(Data("pc.bag"), lidar, imu, ReadWindow(), inline_io);
  auto b = OpenSensorStream(Data("pc.bag"), lidar, imu, ReadWindow(), thread_io);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ((*a)->lidar_layout(), (*b)->lidar_layout());
  const Delivered da = ReadAll(a->get()), db = ReadAll(b->get());
  EXPECT_TRUE(da.error.ok() && db.error.ok());
  EXPECT_EQ(da.stamps, db.stamps);
  EXPECT_EQ(da.scans_so_far, db.scans_so_far);
  EXPECT_EQ((*a)->stats().imu_samples, (*b)->stats().imu_samples);
  // Stopping after a few messages: the destructor joins a blocked producer.
  for (int n : {0, 1, 5}) {
    auto c = OpenSensorStream(Data("pc.bag"), lidar, imu, ReadWindow(), thread_io);
    ASSERT_TRUE(c.ok());
    EXPECT_EQ(ReadAll(c->get(), n).stamps.size(), static_cast<size_t>(n));
  }
}

TEST_F(InputStreamTest, StreamAppliesTheTimeOffsetToEveryScanTime) {
  LidarOptions lidar;
  lidar.type = "ouster";
  ReaderOptions io;
  auto plain = OpenSensorStream(Data("off.bag"), lidar, ImuOptions(), ReadWindow(), io);
  lidar.time_offset = kInjectedOffsetS;
  auto shifted = OpenSensorStream(Data("off.bag"), lidar, ImuOptions(), ReadWindow(), io);
  auto truth = OpenSensorStream(Data("pc.bag"), LidarOptions{}, ImuOptions(), ReadWindow(), io);
  ASSERT_TRUE(plain.ok() && shifted.ok() && truth.ok());
  ImuSample imu;
  Scan s0, s1, s2;
  for (;;) {
    StatusOr<SensorMessage> m = (*shifted)->Next(&imu, &s1);
    ASSERT_TRUE(m.ok());
    if (*m == SensorMessage::kScan) break;
  }
  for (auto* r : {plain->get(), truth->get()}) {
    Scan* out = r == plain->get() ? &s0 : &s2;
    for (;;) {
      StatusOr<SensorMessage> m = r->Next(&imu, out);
      ASSERT_TRUE(m.ok());
      if (*m == SensorMessage::kScan) break;
    }
  }
  const TimeNs offset_ns = SecondsToNs(kInjectedOffsetS);
  EXPECT_EQ(s1.t_start_ns, s0.t_start_ns + offset_ns);
  EXPECT_EQ(s1.t_end_ns, s0.t_end_ns + offset_ns);
  ASSERT_EQ(s1.points.size(), s0.points.size());
  EXPECT_EQ(s1.points.back().t_ns, s0.points.back().t_ns + offset_ns);
  // ... and lands on the true times of the synchronized recording.
  EXPECT_EQ(s1.t_start_ns, s2.t_start_ns);
  EXPECT_EQ(s1.t_end_ns, s2.t_end_ns);
}

}  // namespace
}  // namespace rvlio

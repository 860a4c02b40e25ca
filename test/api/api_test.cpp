// The whole-recording API (rvlio/api.h) in-process: the same results with and
// without an output folder, stop and progress callbacks, refine from an
// in-memory trajectory, evaluation, and errors as Status (never a crash or
// an exit). That the command writes the API's files byte for byte is checked
// by scripts/install_test.sh against the installed tool.
#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_util.h"
#include "rvlio/api.h"
#include "rvlio/api/result_json.h"
#include "rvlio/outputs/run_outputs.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/outputs/scan_columns.h"

namespace rvlio {
namespace {

using testing_cli::MakeTempDir;
using testing_cli::ReadFile;

class ApiTest : public ::testing::Test {
 protected:
  // One 5 s, 512-column simulated tunnel for the suite.
  static void SetUpTestSuite() {
    dir_ = MakeTempDir("rvlio_api");
    SimulateArgs sim;
    sim.out_dir = dir_ + "/data";
    sim.seed = 5;
    sim.duration_s = 5.0;
    sim.overrides = {"lidar.columns=512"};
    StatusOr<SimulateResult> r = SimulateRecording(sim);
    ASSERT_TRUE(r.ok()) << r.status().message();
    recording_ = *r;
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  static RunArgs Run(const std::string& out_dir) {
    StatusOr<Configuration> config = LoadConfig({recording_.config_path}, {});
    EXPECT_TRUE(config.ok()) << config.status().message();
    RunArgs args;
    args.bag = recording_.bag_path;
    args.options = config.ok() ? *config : Configuration();
    args.out_dir = out_dir;
    return args;
  }

  static std::string dir_;
  static SimulateResult recording_;
};
std::string ApiTest::dir_;
SimulateResult ApiTest::recording_;

TEST_F(ApiTest, SimulateReportsWhatItWrote) {
  EXPECT_EQ(recording_.bag_path, dir_ + "/data/tunnel.bag");
  EXPECT_EQ(recording_.bag_path, SimulatedRecordingPath([] {
              SimulateArgs a;
              a.out_dir = dir_ + "/data";
              return a;
            }()));
  EXPECT_EQ(recording_.scans, 50);  // 5 s at 10 Hz
  EXPECT_EQ(recording_.cols, 512);
  EXPECT_FALSE(recording_.stopped);
  for (const std::string& p : {recording_.bag_path, recording_.gt_path, recording_.config_path})
    EXPECT_TRUE(std::filesystem::is_regular_file(p)) << p;
}

TEST_F(ApiTest, RunWithAndWithoutOutputFolderGivesTheSameTrajectory) {
  StatusOr<RunResult> quiet = RunRecording(Run(""));
  ASSERT_TRUE(quiet.ok()) << quiet.status().message();
  EXPECT_FALSE(quiet->written);
  const std::string out = dir_ + "/run";
  int calls = 0;
  double last_fraction = -1.0;
  RunArgs args = Run(out);
  args.progress = [&](const RunProgress& p) {
    ++calls;
    EXPECT_GE(p.fraction, last_fraction);
    ASSERT_NE(p.divergence, nullptr);
    last_fraction = p.fraction;
  };
  StatusOr<RunResult> written = RunRecording(args);
  ASSERT_TRUE(written.ok()) << written.status().message();
  EXPECT_TRUE(written->written);
  EXPECT_GT(calls, 900);  // once per message: ~1000 IMU samples and 50 scans
  EXPECT_NEAR(last_fraction, 1.0, 0.05);

  ASSERT_EQ(quiet->trajectory.size(), written->trajectory.size());
  ASSERT_GT(quiet->scans.size(), 30u);
  EXPECT_EQ(quiet->scans.size(), quiet->trajectory.size());
  EXPECT_EQ(quiet->rss_mb.size(), quiet->scans.size());
  for (size_t i = 0; i < quiet->trajectory.size(); ++i) {
    EXPECT_EQ(quiet->trajectory[i].t_ns, written->trajectory[i].t_ns);
    EXPECT_EQ(quiet->trajectory[i].p_world_imu, written->trajectory[i].p_world_imu) << i;
  }
  // The files are what the result holds.
  StatusOr<Trajectory> tum = ReadTum(out + "/trajectory.tum");
  ASSERT_TRUE(tum.ok()) << tum.status().message();
  ASSERT_EQ(tum->size(), written->trajectory.size());
  EXPECT_NEAR((tum->back().p_world_imu - written->trajectory.back().p_world_imu).norm(), 0.0, 1e-6);
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(out + "/summary.json"));
  EXPECT_EQ(summary["scan_count"], written->scans.size());
  EXPECT_EQ(summary["version"], RVLIO_VERSION);
  EXPECT_EQ(ReadFile(out + "/summary.json"), written->summary_json);  // the text written
  EXPECT_EQ(summary["per_scan_ms"]["median"].get<double>(), written->per_scan.median_ms);
  EXPECT_EQ(summary["sequence_duration_s"].get<double>(), written->sequence_duration_s);
  EXPECT_FALSE(summary["interrupted"].get<bool>());
  for (const char* f : {"map.pcd", "scans.csv"})
    EXPECT_TRUE(std::filesystem::is_regular_file(out + "/" + f)) << f;
  // scans.csv has the columns of the table (outputs/scan_columns.h), in its order.
  StatusOr<ScanTable> csv = ReadScanTable(out + "/scans.csv");
  ASSERT_TRUE(csv.ok()) << csv.status().message();
  std::vector<std::string> table_names;
  for (const ScanColumn* c : ScanColumnsOf(written->scans)) table_names.push_back(c->name);
  EXPECT_EQ(csv->names, table_names);
  ASSERT_EQ(csv->columns[0].size(), written->scans.size());
  for (size_t i = 0; i < written->scans.size(); ++i) {
    EXPECT_NEAR((*csv->Find("vx"))[i], written->scans[i].v_world_imu.x(), 1e-6) << i;
    EXPECT_NEAR((*csv->Find("rss_mb"))[i], written->rss_mb[i], 1e-6 * written->rss_mb[i]) << i;
  }
  EXPECT_FALSE(std::filesystem::exists(out + "/trajectory.partial.tum"));

  // Evaluation of the written file equals that of the in-memory trajectory.
  StatusOr<EvalResult> from_files = EvaluateFiles(recording_.gt_path, out + "/trajectory.tum", {});
  ASSERT_TRUE(from_files.ok()) << from_files.status().message();
  StatusOr<Trajectory> gt = ReadTum(recording_.gt_path);
  ASSERT_TRUE(gt.ok());
  StatusOr<EvalResult> direct = Evaluate(*gt, *tum, {});
  ASSERT_TRUE(direct.ok());
  EXPECT_EQ(from_files->ape_m.rmse, direct->ape_m.rmse);
  EXPECT_LT(from_files->ape_m.rmse, 0.05);  // measured ~0.01 m on this short tunnel
  const nlohmann::json j = EvalJson(*from_files);
  EXPECT_EQ(j["matched"], from_files->matched);
  EXPECT_NEAR(j["ape"]["rmse"].get<double>(), from_files->ape_m.rmse, 1e-9);
}

// Every point of map.pcd is one return with its attributes, for both
// backends: the intensity and ring the recording gives, a time inside the
// scan its scan_index names (a row of trajectory.tum: from the previous
// row's stamp to its own).
TEST_F(ApiTest, MapPointsKeepTheirReturnsAttributesInBothBackends) {
  for (const Backend backend : {Backend::kIeskf, Backend::kSmoother}) {
    const std::string out = dir_ + "/attributes_" + EnumName(backend);
    RunArgs args = Run(out);
    args.options.backend = backend;
    StatusOr<RunResult> run = RunRecording(args);
    ASSERT_TRUE(run.ok()) << run.status().message();
    StatusOr<MapCloudFile> read = ReadMapCloud(out + "/map.pcd");
    ASSERT_TRUE(read.ok()) << read.status().message();
    const MapCloud& map = read->map;
    ASSERT_TRUE(map.has_intensity && map.has_time && map.has_ring && map.has_scan_index);
    ASSERT_GT(map.size(), 5000u) << EnumName(backend);
    std::vector<int> per_scan(run->trajectory.size(), 0);
    size_t bright = 0;
    for (size_t i = 0; i < map.size(); ++i) {
      const uint32_t k = map.scan_index[i];
      ASSERT_LT(k, run->trajectory.size()) << i;
      ++per_scan[k];
      // The map stores UNIX seconds in a double: 0.24 us of rounding.
      EXPECT_LE(map.t_ns[i], run->trajectory[k].t_ns + 1000) << i;
      if (k > 0) {
        EXPECT_GT(map.t_ns[i], run->trajectory[k - 1].t_ns - 1000) << i;
      }
      EXPECT_LT(map.ring[i], 32) << "the simulated OS1-32's beams";
      bright += map.intensity[i] > 0.0f;
    }
    EXPECT_GT(bright, map.size() * 9 / 10) << "the simulator's returns all have an intensity";
    // The survivors come from many scans, not the first one only.
    EXPECT_GT(std::count_if(per_scan.begin(), per_scan.end(), [](int n) { return n > 0; }),
              static_cast<long>(per_scan.size() / 2)) << EnumName(backend);
  }
}

// An opened source instead of the recording (as `rvlio live` hands over its
// network input): the same scans; on_result sees each once, in order;
// annotate_summary edits summary.json before it is written.
TEST_F(ApiTest, AnOpenedSourceGivesTheRecordingsRunAndEveryResultOnce) {
  StatusOr<RunResult> bag = RunRecording(Run(""));
  ASSERT_TRUE(bag.ok()) << bag.status().message();
  RunArgs args = Run(dir_ + "/source");
  StatusOr<std::unique_ptr<SensorBagReader>> source = OpenSensorStream(
      args.bag, args.options.lidar, args.options.imu, ReadWindow(), args.options.io);
  ASSERT_TRUE(source.ok()) << source.status().message();
  args.bag = "network";
  args.source = source->get();
  std::vector<TimeNs> seen;
  args.on_result = [&](const ScanResult& r, const Odometry& odo, const LocalOrigin&) {
    seen.push_back(r.t_ns);
    EXPECT_EQ(odo.stats().scans_processed, static_cast<int64_t>(seen.size()));
  };
  StatusOr<RunResult> run =
      RunRecordingAnnotated(args, [](nlohmann::json* j) { (*j)["extra"] = 7; });
  ASSERT_TRUE(run.ok()) << run.status().message();
  ASSERT_EQ(run->trajectory.size(), bag->trajectory.size());
  ASSERT_EQ(seen.size(), run->scans.size());
  for (size_t i = 0; i < seen.size(); ++i) {
    EXPECT_EQ(seen[i], bag->trajectory[i].t_ns);
    EXPECT_EQ(run->trajectory[i].p_world_imu, bag->trajectory[i].p_world_imu) << i;
  }
  const nlohmann::json summary =
      nlohmann::json::parse(ReadFile(dir_ + "/source/summary.json"), nullptr, false);
  EXPECT_EQ(summary["extra"], 7);
  EXPECT_EQ(summary["bag"], "network");
  // A window needs a recording.
  args.window.start_s = 1.0;
  EXPECT_FALSE(RunRecording(args).ok());
}

TEST_F(ApiTest, StopEndsTheRunAndRecordsTheReason) {
  const std::string out = dir_ + "/stopped";
  RunArgs args = Run(out);
  int polls = 0;
  args.stop = [&polls] { return ++polls > 800 ? std::string("test stop") : std::string(); };
  StatusOr<RunResult> r = RunRecording(args);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_TRUE(r->stopped);
  EXPECT_EQ(r->stop_reason, "test stop");
  EXPECT_FALSE(r->scans.empty());
  EXPECT_LT(r->scans.size(), 45u);
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(out + "/summary.json"));
  EXPECT_TRUE(summary["interrupted"].get<bool>());
  EXPECT_EQ(summary["signal"], "test stop");

  // Stopped before the first scan: a result without scans, nothing written.
  RunArgs early = Run(dir_ + "/stopped_early");
  early.stop = [] { return std::string("now"); };
  StatusOr<RunResult> e = RunRecording(early);
  ASSERT_TRUE(e.ok()) << e.status().message();
  EXPECT_TRUE(e->stopped);
  EXPECT_TRUE(e->scans.empty());
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/stopped_early"));
}

// The progress is the share of the work asked for: with --start/--duration
// it ends near 100 %, not at the share of the whole recording.
TEST_F(ApiTest, ProgressCountsTheWindowAskedFor) {
  RunArgs args = Run("");
  args.window.start_s = 1.0;
  args.window.duration_s = 2.0;  // of the 5 s recording
  double last = -1.0;
  args.progress = [&last](const RunProgress& p) { last = p.fraction; };
  StatusOr<RunResult> r = RunRecording(args);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_GT(last, 0.9);
  EXPECT_LT(last, 1.1);
}

TEST_F(ApiTest, RefineFromAnInMemoryTrajectory) {
  StatusOr<RunResult> run = RunRecording(Run(""));
  ASSERT_TRUE(run.ok()) << run.status().message();
  RefineArgs args;
  args.bag = recording_.bag_path;
  args.init = run->trajectory;
  args.options = Run("").options;
  args.options.refine.rounds = 1;
  args.out_dir = dir_ + "/refine";
  int rounds = 0;
  args.on_round = [&rounds](const RefineRound&) { ++rounds; };
  StatusOr<RefineRunResult> r = RefineRecording(args);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(rounds, 1);
  EXPECT_TRUE(r->read_complete);
  EXPECT_FALSE(r->stopped);
  EXPECT_TRUE(r->written);
  EXPECT_EQ(r->refine.trajectory.size(), run->trajectory.size());
  EXPECT_EQ(nlohmann::json::parse(r->summary_json)["command"], "refine");
  EXPECT_EQ(ReadFile(args.out_dir + "/summary.json"), r->summary_json);
  EXPECT_TRUE(r->chunk_json.empty());  // not a chunk job
  EXPECT_TRUE(std::filesystem::is_regular_file(args.out_dir + "/trajectory.tum"));
}

TEST_F(ApiTest, BadInputIsAStatus) {
  RunArgs missing = Run("");
  missing.bag = dir_ + "/no_such.bag";
  StatusOr<RunResult> r = RunRecording(missing);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(r.status().message().find("no_such.bag"), std::string::npos) << r.status().message();

  RunArgs wrong_topic = Run(dir_ + "/wrong_topic");
  wrong_topic.options.lidar.topic = "/nothing";
  r = RunRecording(wrong_topic);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("/nothing"), std::string::npos) << r.status().message();
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/wrong_topic/summary.json"));

  SimulateArgs sim;
  sim.out_dir = dir_ + "/sim_bad";
  sim.format = "zip";
  StatusOr<SimulateResult> s = SimulateRecording(sim);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("'zip'"), std::string::npos) << s.status().message();

  RefineArgs refine;
  refine.bag = recording_.bag_path;
  refine.init_path = dir_ + "/no_init.tum";
  StatusOr<RefineRunResult> f = RefineRecording(refine);
  ASSERT_FALSE(f.ok());
  EXPECT_NE(f.status().message().find("no_init.tum"), std::string::npos) << f.status().message();

  StatusOr<EvalResult> e = EvaluateFiles(recording_.gt_path, dir_ + "/none.tum", {});
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().code(), StatusCode::kInvalidInput);
}

}  // namespace
}  // namespace rvlio

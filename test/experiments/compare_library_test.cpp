// rvlio/experiments/compare.h in-process: the typed rows (the trajectories in
// memory equal the files the runs wrote, the figures equal `Evaluate` on
// those files), the progress callback once per step, a stop, and bad input
// refused before anything is written. One short simulated tunnel for the
// suite; the whole comparison runs in one case (Release only,
// scripts/sanitize.sh).
#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../cli/cli_util.h"
#include "rvlio/api.h"
#include "rvlio/experiments/compare.h"
#include "rvlio/formats/trajectory_io.h"

namespace rvlio::experiments {
namespace {

namespace fs = std::filesystem;
using testing_cli::MakeTempDir;
using testing_cli::ReadFile;

class CompareLibraryTest : public ::testing::Test {
 protected:
  // A 3 s, 256-column tunnel for the suite.
  static void SetUpTestSuite() {
    dir_ = MakeTempDir("rvlio_compare_lib");
    SimulateArgs sim;
    sim.out_dir = dir_ + "/data";
    sim.seed = 3;
    sim.duration_s = 3.0;
    sim.overrides = {"lidar.columns=256"};
    StatusOr<SimulateResult> r = SimulateRecording(sim);
    ASSERT_TRUE(r.ok()) << r.status().message();
    recording_ = new SimulateResult(*r);
  }
  static void TearDownTestSuite() {
    delete recording_;
    fs::remove_all(dir_);
  }

  static CompareRequest Request(const std::string& out) {
    CompareRequest req;
    req.bag = recording_->bag_path;
    req.gt = recording_->gt_path;
    req.config_files = {recording_->config_path};
    req.out_dir = out;
    return req;
  }

  static std::string dir_;
  static SimulateResult* recording_;
};
std::string CompareLibraryTest::dir_;
SimulateResult* CompareLibraryTest::recording_ = nullptr;

struct SeenStep {
  int index, count;
  bool finished;
  std::string name;
};

// Each row's trajectory equals its run's trajectory.tum, and its figures
// equal Evaluate on that file.
void CheckRowsAgainstFiles(const CompareResult& result, const std::string& out,
                           const Trajectory& truth) {
  for (const CompareRow& row : result.rows) {
    SCOPED_TRACE(row.name);
    ASSERT_TRUE(row.measured()) << row.run_error.message() << row.eval_error;
    EXPECT_EQ(row.exit_code, 0);
    EXPECT_GT(row.scans, 0);
    StatusOr<Trajectory> file = ReadTum(out + "/" + row.name + "/trajectory.tum");
    ASSERT_TRUE(file.ok()) << file.status().message();
    ASSERT_EQ(row.trajectory.size(), file->size());
    for (size_t i = 0; i < file->size(); ++i) {
      EXPECT_EQ(row.trajectory[i].t_ns, (*file)[i].t_ns);
      EXPECT_EQ(row.trajectory[i].p_world_imu, (*file)[i].p_world_imu);
      EXPECT_EQ(row.trajectory[i].q_world_imu.coeffs(), (*file)[i].q_world_imu.coeffs());
    }
    StatusOr<EvalResult> e = Evaluate(truth, *file, EvalOptions());
    ASSERT_TRUE(e.ok());
    EXPECT_EQ(row.eval->ape_m.rmse, e->ape_m.rmse);
    EXPECT_EQ(row.eval->along_axis.max_abs_m, e->along_axis.max_abs_m);
  }
}

// on_step: once when each step starts, once when it has finished.
void CheckSteps(const std::vector<SeenStep>& steps, const CompareResult& result) {
  const size_t runs = result.rows.size();
  ASSERT_EQ(steps.size(), 2 * runs);
  for (size_t i = 0; i < runs; ++i) {
    const SeenStep& start = steps[2 * i];
    const SeenStep& end = steps[2 * i + 1];
    EXPECT_FALSE(start.finished);
    EXPECT_TRUE(end.finished);
    EXPECT_EQ(start.index, static_cast<int>(i));
    EXPECT_EQ(end.index, static_cast<int>(i));
    EXPECT_EQ(end.count, static_cast<int>(runs));
    EXPECT_EQ(start.name, result.rows[i].name);
    EXPECT_EQ(end.name, result.rows[i].name);
  }
}

TEST_F(CompareLibraryTest, TypedRowsInMemoryEqualTheRunFilesAndTheCallbackComesOncePerRun) {
  CompareRequest req = Request(dir_ + "/compare");
  std::vector<SeenStep> steps;
  req.on_step = [&steps](const CompareStep& s) {
    steps.push_back({s.index, s.count, s.finished, s.row->name});
  };
  StatusOr<CompareResult> result = RunCompare(req);
  ASSERT_TRUE(result.ok()) << result.status().message();
  ASSERT_EQ(result->rows.size(), StandardVariants().size() + 1);
  EXPECT_FALSE(result->interrupted);
  StatusOr<Trajectory> truth = ReadTrajectory(recording_->gt_path);
  ASSERT_TRUE(truth.ok());
  CheckRowsAgainstFiles(*result, req.out_dir, *truth);
  CheckSteps(steps, *result);
  const CompareRow& refine = result->rows.back();
  EXPECT_EQ(refine.name, kRefineStep);
  const CompareRow* best = nullptr;  // refine starts from the variant with the smallest ATE
  for (size_t i = 0; i + 1 < result->rows.size(); ++i)
    if (!best || result->rows[i].eval->ape_m.rmse < best->eval->ape_m.rmse)
      best = &result->rows[i];
  ASSERT_NE(best, nullptr);
  EXPECT_EQ(refine.init, best->name);
  // The tables come from the typed rows, not from files.
  EXPECT_FALSE(fs::exists(req.out_dir + "/compare.csv"));
  ASSERT_TRUE(WriteCompareTables(req, *result).ok());
  EXPECT_EQ(ReadFile(req.out_dir + "/compare.csv"), CompareCsv(req, *result));
  EXPECT_EQ(ReadFile(req.out_dir + "/compare.md"), CompareMarkdown(req, *result));
  const std::string csv = CompareCsv(req, *result);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), static_cast<long>(result->rows.size() + 1));
}

TEST_F(CompareLibraryTest, AStopMarksTheRemainingStepsInterrupted) {
  CompareRequest req = Request(dir_ + "/stopped");
  int finished = 0;
  req.on_step = [&finished](const CompareStep& s) { finished += s.finished ? 1 : 0; };
  req.stop = [&finished] { return finished >= 1 ? std::string("SIGINT") : std::string(); };
  req.stop_exit_code = [] { return 130; };
  req.refine = true;
  StatusOr<CompareResult> r = RunCompare(req);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_TRUE(r->interrupted);
  ASSERT_EQ(r->rows.size(), StandardVariants().size() + 1);
  EXPECT_TRUE(r->rows[0].measured());
  for (size_t i = 1; i < r->rows.size(); ++i) {
    EXPECT_TRUE(r->rows[i].interrupted) << r->rows[i].name;
    EXPECT_EQ(r->rows[i].exit_code, 130);
    EXPECT_STREQ(r->rows[i].StatusName(), "interrupted");
    EXPECT_FALSE(fs::exists(req.out_dir + "/" + r->rows[i].name)) << r->rows[i].name;
  }
  EXPECT_EQ(finished, static_cast<int>(r->rows.size()));  // once per step, run or not
}

TEST_F(CompareLibraryTest, BadInputIsRefusedBeforeAnyRun) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"gt", "--gt"}, {"set", "backend"}, {"bag", ""}};
  for (const auto& [what, expected] : cases) {
    CompareRequest req = Request(dir_ + "/bad_" + what);
    if (what == "gt") req.gt = dir_ + "/missing.tum";
    if (what == "set") req.overrides = {"backend=nonsense"};
    if (what == "bag") req.bag = dir_ + "/missing.bag";
    int steps = 0;
    req.on_step = [&steps](const CompareStep&) { ++steps; };
    StatusOr<CompareResult> r = RunCompare(req);
    ASSERT_FALSE(r.ok()) << what;
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidInput) << what;
    EXPECT_NE(r.status().message().find(expected), std::string::npos) << r.status().message();
    EXPECT_EQ(r.status().message().find('\n'), std::string::npos) << r.status().message();
    EXPECT_EQ(steps, 0) << what;
    EXPECT_FALSE(fs::exists(req.out_dir)) << what;
  }
}

}  // namespace
}  // namespace rvlio::experiments

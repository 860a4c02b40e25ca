// rvlio/experiments/compare.h in-process: the typed rows (the trajectories in
// memory equal the files the runs wrote, the figures equal `Evaluate` on
// those files), the progress callback once per step, a stop, and bad input
// refused before anything is written. One short simulated tunnel for the
// suite; the whole comparison runs once.
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
  // A 4 s, 256-column tunnel, compared once (4 variants and refine).
  static void SetUpTestSuite() {
    dir_ = MakeTempDir("rvlio_compare_lib");
    SimulateArgs sim;
    sim.out_dir = dir_ + "/data";
    sim.seed = 3;
    sim.duration_s = 4.0;
    sim.overrides = {"lidar.columns=256"};
    StatusOr<SimulateResult> r = SimulateRecording(sim);
    ASSERT_TRUE(r.ok()) << r.status().message();
    recording_ = new SimulateResult(*r);
    CompareRequest req = Request(dir_ + "/compare");
    req.on_step = [](const CompareStep& s) {
      steps_.push_back({s.index, s.count, s.finished, s.row->name});
    };
    StatusOr<CompareResult> c = RunCompare(req);
    ASSERT_TRUE(c.ok()) << c.status().message();
    result_ = new CompareResult(std::move(*c));
  }
  static void TearDownTestSuite() {
    delete result_;
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

  struct SeenStep {
    int index, count;
    bool finished;
    std::string name;
  };
  static std::string dir_;
  static SimulateResult* recording_;
  static CompareResult* result_;
  static std::vector<SeenStep> steps_;
};
std::string CompareLibraryTest::dir_;
SimulateResult* CompareLibraryTest::recording_ = nullptr;
CompareResult* CompareLibraryTest::result_ = nullptr;
std::vector<CompareLibraryTest::SeenStep> CompareLibraryTest::steps_;

TEST_F(CompareLibraryTest, RowsAreTypedAndTheTrajectoriesInMemoryEqualTheFiles) {
  ASSERT_NE(result_, nullptr);
  ASSERT_EQ(result_->rows.size(), StandardVariants().size() + 1);
  StatusOr<Trajectory> truth = ReadTrajectory(recording_->gt_path);
  ASSERT_TRUE(truth.ok());
  for (const CompareRow& row : result_->rows) {
    SCOPED_TRACE(row.name);
    ASSERT_TRUE(row.measured()) << row.run_error.message() << row.eval_error;
    EXPECT_EQ(row.exit_code, 0);
    EXPECT_GT(row.scans, 0);
    StatusOr<Trajectory> file = ReadTum(dir_ + "/compare/" + row.name + "/trajectory.tum");
    ASSERT_TRUE(file.ok()) << file.status().message();
    ASSERT_EQ(row.trajectory.size(), file->size());
    for (size_t i = 0; i < file->size(); ++i) {
      EXPECT_EQ(row.trajectory[i].t_ns, (*file)[i].t_ns);
      EXPECT_EQ(row.trajectory[i].p_world_imu, (*file)[i].p_world_imu);
      EXPECT_EQ(row.trajectory[i].q_world_imu.coeffs(), (*file)[i].q_world_imu.coeffs());
    }
    StatusOr<EvalResult> e = Evaluate(*truth, *file, EvalOptions());
    ASSERT_TRUE(e.ok());
    EXPECT_EQ(row.eval->ape_m.rmse, e->ape_m.rmse);
    EXPECT_EQ(row.eval->along_axis.max_abs_m, e->along_axis.max_abs_m);
  }
  const CompareRow& refine = result_->rows.back();
  EXPECT_EQ(refine.name, kRefineStep);
  ASSERT_NE(result_->Best(), nullptr);
  EXPECT_FALSE(refine.init.empty());
  EXPECT_FALSE(result_->interrupted);
}

TEST_F(CompareLibraryTest, ProgressCallbackIsCalledOnceAtTheStartAndOnceAtTheEndOfEachRun) {
  ASSERT_NE(result_, nullptr);
  const size_t runs = result_->rows.size();
  ASSERT_EQ(steps_.size(), 2 * runs);
  for (size_t i = 0; i < runs; ++i) {
    const SeenStep& start = steps_[2 * i];
    const SeenStep& end = steps_[2 * i + 1];
    EXPECT_FALSE(start.finished);
    EXPECT_TRUE(end.finished);
    EXPECT_EQ(start.index, static_cast<int>(i));
    EXPECT_EQ(end.index, static_cast<int>(i));
    EXPECT_EQ(end.count, static_cast<int>(runs));
    EXPECT_EQ(start.name, result_->rows[i].name);
    EXPECT_EQ(end.name, result_->rows[i].name);
  }
}

TEST_F(CompareLibraryTest, TablesAreWrittenFromTheTypedResult) {
  ASSERT_NE(result_, nullptr);
  const CompareRequest req = Request(dir_ + "/compare");
  ASSERT_TRUE(WriteCompareTables(req, *result_).ok());
  EXPECT_EQ(ReadFile(req.out_dir + "/compare.csv"), CompareCsv(req, *result_));
  EXPECT_EQ(ReadFile(req.out_dir + "/compare.md"), CompareMarkdown(req, *result_));
  const std::string csv = CompareCsv(req, *result_);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), static_cast<long>(result_->rows.size() + 1));
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

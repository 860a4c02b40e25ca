// End to end: `rvlio simulate` writes the true localizability, `rvlio run`
// (IESKF, default RV) detects degeneracy, `rvlio eval --degeneracy` scores it
// (docs/degeneracy_truth.md). The planar featureless tunnel is degenerate
// along its axis on every scan; RV must find most of them and their axis.
// Then the contract columns of scans.csv, and bad input (exit 2, one line).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "cli_util.h"

namespace rvlio {
namespace {

using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

class DegeneracyEvalCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing_cli::MakeTempDir("rvlio_degeneracy_cli");
    ASSERT_FALSE(dir_.empty());
    const ToolRun sim = testing_cli::CachedSimulate(
        "--preset featureless --seed 4 --duration 6 --set lidar.columns=512", dir_ + "/sim", dir_);
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
    const ToolRun run = RunTool("run --bag " + dir_ + "/sim/featureless.bag --config " + dir_ +
                                    "/sim/featureless.yaml --quiet --out " + dir_ + "/run",
                                dir_);
    ASSERT_EQ(run.exit_code, 0) << run.err;
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  // A copy of the run folder to corrupt.
  static std::string CopyRun(const std::string& name) {
    const std::string out = dir_ + "/" + name;
    std::filesystem::copy(dir_ + "/run", out, std::filesystem::copy_options::recursive);
    return out;
  }
  static nlohmann::json Score(const std::string& run_dir, const std::string& extra = "") {
    const ToolRun r =
        RunTool("eval --degeneracy " + run_dir + " --truth " + dir_ + "/sim --json " + extra, dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out, nullptr, false);
  }
  static std::string dir_;
};
std::string DegeneracyEvalCli::dir_;

TEST_F(DegeneracyEvalCli, PlanarTunnelTruthIsDegenerateAndRvFindsItsAxis) {
  const std::string csv = ReadFile(dir_ + "/sim/localizability.csv");
  std::istringstream lines(csv);
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line.rfind("t,points,lambda_min,lambda_mid,lambda_max,weak_dir_x,", 0), 0u) << line;
  int rows = 0, degenerate = 0;
  while (std::getline(lines, line)) {
    ++rows;
    degenerate += line.back() == '1';
  }
  EXPECT_EQ(rows, 60);
  EXPECT_EQ(degenerate, rows);

  const nlohmann::json j = Score(dir_ + "/run");
  ASSERT_FALSE(j.is_discarded());
  EXPECT_EQ(j["detection_columns"], "degenerate,weak_dir");  // the run writes them
  EXPECT_GT(j["matched"].get<int>(), 40);
  EXPECT_EQ(j["false_positive"].get<int>(), 0);
  EXPECT_GT(j["recall"].get<double>(), 0.8);
  EXPECT_LT(j["angle_deg"]["mean"].get<double>(), 5.0);
  EXPECT_GT(j["along_weak"]["path_length"].get<double>(), 0.5);

  // The text table and a stricter truth threshold (all ratios are 0 here).
  const ToolRun text = RunTool("eval --degeneracy " + dir_ + "/run --truth " + dir_ + "/sim", dir_);
  EXPECT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("recall"), std::string::npos) << text.out;
  EXPECT_EQ(Score(dir_ + "/run", "--truth-ratio 0.001")["false_negative"], j["false_negative"]);
}

// A scans.csv of an older run, without the degeneracy columns, is scored by
// RV's own (rv_active, n_alpha_*): for the default method the same detection.
TEST_F(DegeneracyEvalCli, OlderRunIsScoredByTheRvColumns) {
  const std::string run = CopyRun("older");
  std::istringstream in(ReadFile(run + "/scans.csv"));
  const std::vector<std::string> dropped = {"degeneracy_method", "degenerate", "weak_dirs",
                                            "weak_dir_x", "weak_dir_y", "weak_dir_z",
                                            "condition_number"};
  std::vector<bool> keep;
  std::ostringstream out;
  for (std::string line; std::getline(in, line);) {
    std::istringstream cells(line);
    std::string cell, row;
    for (size_t i = 0; std::getline(cells, cell, ','); ++i) {
      if (keep.size() <= i)
        keep.push_back(std::find(dropped.begin(), dropped.end(), cell) == dropped.end());
      if (keep[i]) row += (row.empty() ? "" : ",") + cell;
    }
    out << row << '\n';
  }
  ASSERT_EQ(std::count(keep.begin(), keep.end(), false), 7);
  std::ofstream(run + "/scans.csv") << out.str();
  const nlohmann::json older = Score(run), current = Score(dir_ + "/run");
  ASSERT_FALSE(older.is_discarded());
  EXPECT_EQ(older["detection_columns"], "rv_active,n_alpha");
  EXPECT_EQ(older["true_positive"], current["true_positive"]);
  EXPECT_EQ(older["false_positive"], current["false_positive"]);
  EXPECT_NEAR(older["angle_deg"]["mean"].get<double>(), current["angle_deg"]["mean"].get<double>(),
              0.5);
}

// A run with the degeneracy columns (degenerate, weak_dir_*) is read by them:
// a detection copied from the truth scores precision = recall = 1, angle 0.
TEST_F(DegeneracyEvalCli, ContractColumnsAreReadByName) {
  const std::string run = CopyRun("contract");
  std::istringstream truth(ReadFile(dir_ + "/sim/localizability.csv"));
  std::ostringstream scans;
  scans << "t,status,degeneracy_method,degenerate,weak_dirs,weak_dir_x,weak_dir_y,weak_dir_z,"
           "condition_number\n";
  std::string line;
  std::getline(truth, line);
  while (std::getline(truth, line)) {
    std::vector<std::string> f;
    std::istringstream fields(line);
    for (std::string x; std::getline(fields, x, ',');) f.push_back(x);
    scans << f[0] << ",ok,remap,1,1," << f[5] << ',' << f[6] << ',' << f[7] << ",100\n";
  }
  std::ofstream(run + "/scans.csv") << scans.str();
  const nlohmann::json j = Score(run);
  ASSERT_FALSE(j.is_discarded());
  EXPECT_EQ(j["detection_columns"], "degenerate,weak_dir");
  EXPECT_EQ(j["precision"].get<double>(), 1.0);
  EXPECT_EQ(j["recall"].get<double>(), 1.0);
  EXPECT_LT(j["angle_deg"]["max"].get<double>(), 1e-3);
}

TEST_F(DegeneracyEvalCli, BadInputIsOneLineExit2) {
  const std::string base = "eval --degeneracy " + dir_ + "/run";
  testing_cli::ExpectOneErrorLine(RunTool(base, dir_), "eval", "--truth");
  testing_cli::ExpectOneErrorLine(RunTool("eval --truth " + dir_ + "/sim", dir_), "eval",
                                  "--degeneracy");
  testing_cli::ExpectOneErrorLine(RunTool(base + " --truth " + dir_ + "/nowhere", dir_), "eval",
                                  "localizability.csv");
  testing_cli::ExpectOneErrorLine(
      RunTool(base + " --truth " + dir_ + "/sim --truth-ratio -1", dir_), "eval", "--truth-ratio");

  // No detection columns at all.
  const std::string no_columns = CopyRun("no_columns");
  std::ofstream(no_columns + "/scans.csv") << "t,status\n1700000000.1,ok\n";
  testing_cli::ExpectOneErrorLine(
      RunTool("eval --degeneracy " + no_columns + " --truth " + dir_ + "/sim", dir_), "eval",
      "no column 'rv_active'");

  // A non-finite stamp.
  const std::string nan_t = CopyRun("nan_t");
  std::string scans = ReadFile(nan_t + "/scans.csv");
  const size_t row = scans.find('\n') + 1;
  scans.replace(row, scans.find(',', row) - row, "nan");
  std::ofstream(nan_t + "/scans.csv") << scans;
  testing_cli::ExpectOneErrorLine(
      RunTool("eval --degeneracy " + nan_t + " --truth " + dir_ + "/sim", dir_), "eval",
      "t is not a finite number");

  // No scan within max_dt of a true one (every stamp 1000 s late).
  const std::string late = CopyRun("late");
  std::ofstream(late + "/scans.csv") << "t,rv_active,n_alpha_x,n_alpha_y,n_alpha_z\n"
                                     << "1700001000.1,1,1,0,0\n1700001000.2,1,1,0,0\n";
  testing_cli::ExpectOneErrorLine(
      RunTool("eval --degeneracy " + late + " --truth " + dir_ + "/sim", dir_), "eval",
      "scans.csv");

  // Two ground truths in the simulation folder: --gt must name one.
  const std::string two = dir_ + "/two_gt";
  std::filesystem::copy(dir_ + "/sim", two, std::filesystem::copy_options::recursive);
  std::filesystem::copy(two + "/featureless_gt.tum", two + "/other_gt.tum");
  testing_cli::ExpectOneErrorLine(RunTool(base + " --truth " + two, dir_), "eval", "ground truths");
  EXPECT_EQ(RunTool(base + " --truth " + two + " --gt " + two + "/other_gt.tum", dir_).exit_code,
            0);
}

// The truth must be of the run's recording: a simulation of another
// duration (stamps disagree) or of another seed (same stamps; its
// simulation.json names another recording) is refused with one line. A copy
// of the right folder, or an older one without simulation.json, is scored.
TEST_F(DegeneracyEvalCli, TruthOfAnotherSimulationIsRefused) {
  const std::string base = "eval --degeneracy " + dir_ + "/run --truth ";
  const ToolRun shorter = testing_cli::CachedSimulate(
      "--preset featureless --seed 4 --duration 3 --set lidar.columns=512", dir_ + "/sim_3s", dir_);
  ASSERT_EQ(shorter.exit_code, 0) << shorter.err;
  // Its simulation.json names another recording; without the record (an
  // older simulation) the stamps disagree.
  testing_cli::ExpectOneErrorLine(RunTool(base + dir_ + "/sim_3s", dir_), "eval",
                                  "the truth is of another simulation");
  const std::string shorter_older = dir_ + "/sim_3s_older";
  std::filesystem::copy(dir_ + "/sim_3s", shorter_older, std::filesystem::copy_options::recursive);
  ASSERT_TRUE(std::filesystem::remove(shorter_older + "/simulation.json"));
  testing_cli::ExpectOneErrorLine(RunTool(base + shorter_older, dir_), "eval",
                                  "the truth is of another recording");
  const ToolRun seed = testing_cli::CachedSimulate(
      "--preset featureless --seed 5 --duration 6 --set lidar.columns=512", dir_ + "/sim_seed5",
      dir_);
  ASSERT_EQ(seed.exit_code, 0) << seed.err;
  testing_cli::ExpectOneErrorLine(RunTool(base + dir_ + "/sim_seed5", dir_), "eval",
                                  "the truth is of another simulation");

  const std::string copy = dir_ + "/sim_copy";
  std::filesystem::copy(dir_ + "/sim", copy, std::filesystem::copy_options::recursive);
  EXPECT_EQ(RunTool(base + copy, dir_).exit_code, 0);
  const std::string older = dir_ + "/sim_older";
  std::filesystem::copy(dir_ + "/sim", older, std::filesystem::copy_options::recursive);
  ASSERT_TRUE(std::filesystem::remove(older + "/simulation.json"));
  EXPECT_EQ(RunTool(base + older, dir_).exit_code, 0);
}

}  // namespace
}  // namespace rvlio

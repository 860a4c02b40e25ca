// scripts/ablate_paired.py: seed-by-seed comparison of ablation variants with
// a baseline, on a hand-written summary.csv with known answers.
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "cli/cli_util.h"

namespace rvlio::testing_cli {
namespace {

const char* kHeader =
    "id,sequence,variant,seed,status,exit_code,ate_rmse,rpe_rmse,axis_rmse,axis_max,end_point,"
    "ms_per_scan,rtf,rv_active_fraction,wall_s,error\n";

std::string Cell(const std::string& seq, const std::string& variant, int seed, double ate,
                 double axis_rmse, double axis_max, double ms) {
  return seq + "_" + variant + "_s" + std::to_string(seed) + "," + seq + "," + variant + "," +
         std::to_string(seed) + ",done,0," + std::to_string(ate) + ",0.001," +
         std::to_string(axis_rmse) + "," + std::to_string(axis_max) + ",0.1," +
         std::to_string(ms) + ",10,1,1.0,\n";
}

class PairedTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = MakeTempDir("rvlio_paired"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  void Write(const std::string& text) { std::ofstream(dir_ + "/summary.csv") << text; }
  ToolRun Paired(const std::string& args) {
    const std::string cmd = std::string("/usr/bin/python3 ") + RVLIO_SOURCE_DIR +
                            "/scripts/ablate_paired.py " + dir_ + " " + args + " >" + dir_ +
                            "/out.txt 2>" + dir_ + "/err.txt";
    const int status = std::system(cmd.c_str());
    ToolRun r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = ReadFile(dir_ + "/out.txt");
    r.err = ReadFile(dir_ + "/err.txt");
    return r;
  }
  std::string dir_;
};

TEST_F(PairedTest, CountsSeedsBelowTheBaselineAndTheWorstRatio) {
  std::string csv = kHeader;
  // off: ATE 0.1/0.2/0.3; on: 0.08/0.25/0.27 (2 of 3 lower, worst 0.25/0.2 = +25 %).
  csv += Cell("tunnel", "off", 1, 0.10, 0.09, 0.5, 5) + Cell("tunnel", "off", 2, 0.20, 0.19, 0.6, 6) +
         Cell("tunnel", "off", 3, 0.30, 0.29, 0.7, 7);
  csv += Cell("tunnel", "on", 1, 0.08, 0.10, 0.4, 4) + Cell("tunnel", "on", 2, 0.25, 0.18, 0.5, 5) +
         Cell("tunnel", "on", 3, 0.27, 0.20, 0.6, 6);
  // A failed cell leaves its seed out of the pair and is counted.
  csv += "tunnel_broken_s1,tunnel,broken,1,failed,2,,,,,,,,,0.1,exited with status 2\n";
  csv += Cell("tunnel", "broken", 2, 0.1, 0.1, 0.1, 1) + Cell("tunnel", "broken", 3, 0.1, 0.1, 0.1, 1);
  Write(csv);
  const ToolRun r = Paired("");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("| tunnel | off | 3 | 0.2000 | 0.1900 | 0.6000 | - | - | 6.00 | 0 |"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| tunnel | on | 3 | 0.2000 | 0.1600 | 0.5000 | 2 / 2 / 3 of 3 | +25 % | 5.00 | 0 |"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| tunnel | broken | 2 | 0.1000 | 0.1000 | 0.1000 | 2 / 2 / 2 of 2 | -50 % | 1.00 | 1 |"),
            std::string::npos) << r.out;
  // Another baseline and a single metric.
  const ToolRun b = Paired("--baseline on --metric axis_max");
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_NE(b.out.find("| tunnel | off | 3 | 0.6000 | 0 of 3 | +25 % | 6.00 | 0 |"), std::string::npos)
      << b.out;
}

TEST_F(PairedTest, BadInputIsOneLineAndExit2) {
  ToolRun r = Paired("");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("summary.csv: no such file"), std::string::npos) << r.err;
  Write("id,sequence,variant,seed,status,ate_rmse,ms_per_scan\n");
  r = Paired("");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing column(s) axis_rmse, axis_max"), std::string::npos) << r.err;
  Write(std::string(kHeader) + Cell("tunnel", "on", 1, 0.1, 0.1, 0.1, 1));
  r = Paired("");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("baseline variant 'off' is not in the grid (variants: on)"), std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

}  // namespace
}  // namespace rvlio::testing_cli

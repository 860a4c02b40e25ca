// End to end: every degeneracy.method in every backend (IESKF, smoother,
// refine) on a short simulated tunnel (8 s, 512 columns), the scans.csv
// degeneracy columns and the summaries' counts (docs/degeneracy.md).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_util.h"

namespace rvlio {
namespace {

using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

constexpr const char* kColumns =
    "degeneracy_method,degenerate,weak_dirs,weak_dir_x,weak_dir_y,weak_dir_z,condition_number";

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream ss(line);
  std::string f;
  while (std::getline(ss, f, ',')) fields.push_back(f);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

class DegeneracyCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing_cli::MakeTempDir("rvlio_degeneracy_cli");
    const ToolRun r = testing_cli::CachedSimulate(
        "--preset tunnel --seed 1 --duration 8 --set lidar.columns=512", dir_ + "/data", dir_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    data_ = dir_ + "/data/tunnel";
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  ToolRun Run(const std::string& sets, const std::string& out) {
    return RunTool("run --bag " + data_ + ".bag --config " + data_ + ".yaml " + sets +
                       " --quiet --out " + out,
                   dir_);
  }
  std::string dir_, data_;
};

// Per method: exit 0, the columns, the method named on every row, a unit
// weak direction when there is one, and the share of degenerate scans.
TEST_F(DegeneracyCliTest, EveryMethodRunsAndReportsTheDegeneracyColumns) {
  const struct {
    const char* method;
    double min_degenerate, max_degenerate;  // shares of the scans
  } cases[] = {{"none", 0.0, 0.0}, {"rv", 0.3, 1.0}, {"remap", 0.5, 1.0},
               {"localizability", 0.8, 1.0}, {"regularized", 0.0, 1.0}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.method);
    const std::string out = dir_ + "/" + c.method;
    const ToolRun r = Run(std::string("--set degeneracy.method=") + c.method, out);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::istringstream csv(ReadFile(out + "/scans.csv"));
    std::string header, line;
    std::getline(csv, header);
    const size_t at = header.find(kColumns);
    ASSERT_NE(at, std::string::npos) << header;
    const int first = static_cast<int>(std::count(header.begin(), header.begin() + at, ','));
    int rows = 0, degenerate = 0, along_axis = 0;
    while (std::getline(csv, line)) {
      const std::vector<std::string> f = Split(line);
      ASSERT_GE(static_cast<int>(f.size()), first + 7) << line;
      EXPECT_EQ(f[first], c.method);
      ++rows;
      degenerate += f[first + 1] == "1" ? 1 : 0;
      if (f[first + 2] == "0") {
        EXPECT_TRUE(f[first + 3].empty() && f[first + 4].empty() && f[first + 5].empty());
        continue;
      }
      const double x = std::stod(f[first + 3]), y = std::stod(f[first + 4]),
                   z = std::stod(f[first + 5]);
      EXPECT_NEAR(x * x + y * y + z * z, 1.0, 1e-5) << line;
      along_axis += std::abs(x) > 0.9 ? 1 : 0;  // the simulated tunnel runs along world x
    }
    ASSERT_GT(rows, 50);
    EXPECT_GE(degenerate, c.min_degenerate * rows);
    EXPECT_LE(degenerate, c.max_degenerate * rows);
    if (std::string(c.method) == "remap" || std::string(c.method) == "localizability") {
      EXPECT_GE(along_axis, 0.5 * rows);  // the weak direction found is the tunnel's axis
    }
    const nlohmann::json summary =
        nlohmann::json::parse(ReadFile(out + "/summary.json"), nullptr, false);
    ASSERT_FALSE(summary.is_discarded());
    EXPECT_EQ(summary["degenerate_scans"].get<int>(), degenerate);
  }
}

TEST_F(DegeneracyCliTest, AnUnknownMethodExitsTwo) {
  const ToolRun bad = Run("--set degeneracy.method=bogus", dir_ + "/bogus");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("degeneracy.method"), std::string::npos) << bad.err;
}

// The degeneracy columns of a run: the method on every row, and how many
// rows call their scan degenerate (-1 when the columns are missing).
int DegenerateRows(const std::string& scans_csv, const std::string& method) {
  std::istringstream csv(ReadFile(scans_csv));
  std::string header, line;
  std::getline(csv, header);
  const size_t at = header.find(kColumns);
  if (at == std::string::npos) return -1;
  const int first = static_cast<int>(std::count(header.begin(), header.begin() + at, ','));
  int degenerate = 0;
  while (std::getline(csv, line)) {
    const std::vector<std::string> f = Split(line);
    if (static_cast<int>(f.size()) < first + 7 || f[first] != method) return -1;
    degenerate += f[first + 1] == "1" ? 1 : 0;
  }
  return degenerate;
}

// Every method in the smoother and in refine (docs/degeneracy.md
// "Backends"): exit 0, the smoother's per-scan columns filled and counted in
// summary.json, refine's count in its summary, and an accuracy near the
// untreated run's (loose: the treatments hold or damp the tunnel's axis).
TEST_F(DegeneracyCliTest, EveryMethodRunsInTheSmootherAndInRefine) {
  const std::string gt = data_ + "_gt.tum";
  const std::string base = dir_ + "/smoother_none";
  ASSERT_EQ(Run("--set backend=smoother --set degeneracy.method=none", base).exit_code, 0);
  for (const char* method : {"rv", "remap", "localizability", "regularized"}) {
    SCOPED_TRACE(method);
    const std::string sets = std::string("--set degeneracy.method=") + method;
    const std::string smoother = dir_ + "/smoother_" + method;
    const ToolRun s = Run("--set backend=smoother " + sets, smoother);
    ASSERT_EQ(s.exit_code, 0) << s.err;
    const int degenerate = DegenerateRows(smoother + "/scans.csv", method);
    EXPECT_GT(degenerate, 0);
    const nlohmann::json summary =
        nlohmann::json::parse(ReadFile(smoother + "/summary.json"), nullptr, false);
    ASSERT_FALSE(summary.is_discarded());
    EXPECT_EQ(summary["degenerate_scans"].get<int>(), degenerate);
    const nlohmann::json ate = testing_cli::EvalJson(gt, smoother + "/trajectory.tum", dir_);
    ASSERT_TRUE(ate.is_object());
    EXPECT_LT(ate["ape"]["rmse"].get<double>(), 0.05);

    const std::string refine = dir_ + "/refine_" + method;
    const ToolRun r = RunTool("refine --bag " + data_ + ".bag --config " + data_ + ".yaml --init " +
                                  base + "/trajectory.tum --set refine.rounds=2 " + sets +
                                  " --out " + refine,
                              dir_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json rs =
        nlohmann::json::parse(ReadFile(refine + "/summary.json"), nullptr, false);
    ASSERT_FALSE(rs.is_discarded());
    EXPECT_GT(rs["degenerate_scans"].get<int>(), 0);
    EXPECT_EQ(rs["degenerate_scans"].get<int>(), rs["rounds"].back()["degenerate_scans"].get<int>());
    const nlohmann::json rate = testing_cli::EvalJson(gt, refine + "/trajectory.tum", dir_);
    ASSERT_TRUE(rate.is_object());
    EXPECT_LT(rate["ape"]["rmse"].get<double>(), 0.05);
  }
  // remap's project form in refine (degeneracy.remap_refine_form).
  const std::string projected = dir_ + "/refine_remap_project";
  const ToolRun p = RunTool("refine --bag " + data_ + ".bag --config " + data_ + ".yaml --init " +
                                base + "/trajectory.tum --set refine.rounds=2 " +
                                "--set degeneracy.method=remap --set degeneracy.remap_refine_form=project --out " +
                                projected,
                            dir_);
  ASSERT_EQ(p.exit_code, 0) << p.err;
  const nlohmann::json ps = nlohmann::json::parse(ReadFile(projected + "/summary.json"), nullptr, false);
  ASSERT_FALSE(ps.is_discarded());
  EXPECT_GT(ps["degenerate_scans"].get<int>(), 0);
  const nlohmann::json pate = testing_cli::EvalJson(gt, projected + "/trajectory.tum", dir_);
  ASSERT_TRUE(pate.is_object());
  EXPECT_LT(pate["ape"]["rmse"].get<double>(), 0.05);
}

}  // namespace
}  // namespace rvlio

// End to end: `rvlio demo`, the README's first command, on a short simulated
// tunnel: it simulates into DIR/data, runs compare's four variants and refine
// against the ground truth, and writes the tables, the plots and the report.
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_util.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;

// The rows of compare.csv after its header, one string per line.
std::vector<std::string> DemoCsvRows(const std::string& path) {
  std::istringstream in(testing_cli::ReadFile(path));
  std::vector<std::string> rows;
  std::string line;
  for (bool header = true; std::getline(in, line); header = false)
    if (!header && !line.empty()) rows.push_back(line);
  return rows;
}

TEST(DemoTest, ShortDemoSimulatesComparesAndWritesTheReport) {
  const std::string tmp = testing_cli::MakeTempDir("rvlio_demo");
  ASSERT_FALSE(tmp.empty());
  const std::string out = tmp + "/demo";
  const testing_cli::ToolRun r =
      testing_cli::RunTool("demo --duration 4 --out " + out, tmp);
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  for (const char* f : {"data/tunnel.bag", "data/tunnel.yaml", "data/tunnel_gt.tum",
                        "compare.csv", "compare.md", "compare.json", "report.html",
                        "plots/trajectories.png", "refine/trajectory.tum"})
    EXPECT_TRUE(fs::exists(out + "/" + f)) << f;
  const std::vector<std::string> rows = DemoCsvRows(out + "/compare.csv");
  ASSERT_EQ(rows.size(), 5u);  // four run variants and refine
  for (const std::string& row : rows) EXPECT_NE(row.find(",ok,0,"), std::string::npos) << row;
  EXPECT_NE(r.out.find("refine (from "), std::string::npos) << r.out;
  fs::remove_all(tmp);
}

TEST(DemoTest, BadSeedIsOneLineAndExitTwoBeforeAnythingIsWritten) {
  const std::string tmp = testing_cli::MakeTempDir("rvlio_demo_bad");
  ASSERT_FALSE(tmp.empty());
  const testing_cli::ToolRun r = testing_cli::RunTool("demo --seed x --out " + tmp + "/d", tmp);
  testing_cli::ExpectOneErrorLine(r, "demo", "--seed");
  EXPECT_FALSE(fs::exists(tmp + "/d"));
  fs::remove_all(tmp);
}

}  // namespace
}  // namespace rvlio

// `rvlio report` as a command: bad input is one line on stderr and exit 2,
// and nothing is written.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "cli/cli_util.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;
using testing_cli::RunTool;
using testing_cli::ToolRun;

int CountLines(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n' ? 1 : 0;
  return n;
}

TEST(ReportCliTest, BadInputIsOneLineAndExitTwo) {
  const std::string dir = testing_cli::MakeTempDir("rvlio_report_cli");
  ASSERT_FALSE(dir.empty());
  fs::create_directories(dir + "/empty");
  fs::create_directories(dir + "/run");
  std::ofstream(dir + "/run/summary.json") << "{\"scan_count\": 1}";
  std::ofstream(dir + "/run/trajectory.tum") << "1.0 0 0 0 0 0 0 1\n";
  const struct {
    std::string args, expected;
  } cases[] = {
      {"report", "missing the folder"},
      {"report " + dir + "/missing", dir + "/missing: no such folder"},
      {"report " + dir + "/empty", "nothing to report"},
      {"report " + dir + "/run --max-points 0", "--max-points '0'"},
      {"report " + dir + "/run --gt " + dir + "/none.tum", "--gt"},
      {"report " + dir + "/run --bogus", "unknown option --bogus"},
  };
  for (const auto& c : cases) {
    const ToolRun r = RunTool(c.args, dir);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(CountLines(r.err), 1) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find("rvlio report: error: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << "\n" << r.err;
  }
  EXPECT_TRUE(fs::is_empty(dir + "/empty"));
  EXPECT_FALSE(fs::exists(dir + "/run/report.html"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rvlio

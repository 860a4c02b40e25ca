// End to end: `rvlio run` with the scan association on two threads
// (constraints.threads=2) writes the same trajectory.tum and map.pcd, byte for
// byte, as on one thread, for both backends, on the suite's seeded
// 512-column tunnel (docs/speed.md, "k-nearest neighbours and parallel
// association").
#include <string>

#include <gtest/gtest.h>

#include "cli_util.h"

namespace rvlio {
namespace {

using testing_cli::ReadFile;
using testing_cli::ToolRun;

class AssociationThreadsCliTest : public testing_cli::SimulatedTunnelSuite {};

TEST_F(AssociationThreadsCliTest, TwoThreadsWriteTheSameOutputsAsOne) {
  for (const std::string backend : {"ieskf", "smoother"}) {
    SCOPED_TRACE(backend);
    const std::string one = dir_ + "/" + backend + "_1", two = dir_ + "/" + backend + "_2";
    const ToolRun r1 = Run(one, "--quiet --set backend=" + backend);
    ASSERT_EQ(r1.exit_code, 0) << r1.err;
    const ToolRun r2 =
        Run(two, "--quiet --set backend=" + backend + " --set constraints.threads=2");
    ASSERT_EQ(r2.exit_code, 0) << r2.err;
    for (const char* f : {"trajectory.tum", "map.pcd"}) {
      const std::string a = ReadFile(one + "/" + f), b = ReadFile(two + "/" + f);
      EXPECT_GT(a.size(), 1000u) << f;
      EXPECT_TRUE(a == b) << f << " differs between 1 and 2 association threads";
    }
    const auto summary = nlohmann::json::parse(ReadFile(two + "/summary.json"));
    EXPECT_EQ(summary["config"]["constraints"]["threads"], 2);
  }
}

}  // namespace
}  // namespace rvlio

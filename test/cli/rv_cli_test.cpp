// End to end: the RV modules in the IESKF on seeded simulated bags. In the
// tunnel RV (defaults) beats RV off on ATE and along the axis; in a
// feature-rich hall the criterion stays inactive and RV changes nothing that
// matters; in a featureless tunnel it activates on nearly every scan and the
// run completes without NaN (paper Remark 3: the axis itself is unobservable).
#include <cmath>
#include <filesystem>
#include <sstream>

#include <gtest/gtest.h>

#include "cli_util.h"

namespace rvlio {
namespace {

using testing_cli::EvalJson;
using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

struct RvRun {
  nlohmann::json summary, eval;
  std::string trajectory;
};

class RvCliTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing_cli::MakeTempDir("rvlio_rv_cli"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  void Simulate(const std::string& preset, int seconds, int seed = 2, int columns = 512) {
    const ToolRun r = testing_cli::CachedSimulate(
        "--preset " + preset + " --seed " + std::to_string(seed) + " --duration " +
            std::to_string(seconds) + " --set lidar.columns=" + std::to_string(columns),
        dir_ + "/data", dir_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  RvRun Run(const std::string& preset, const std::string& label, const std::string& sets) {
    const std::string data = dir_ + "/data/" + preset, out = dir_ + "/" + label;
    const ToolRun r = RunTool("run --bag " + data + ".bag --config " + data + ".yaml " + sets +
                                  " --quiet --out " + out, dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    RvRun run;
    run.summary = nlohmann::json::parse(ReadFile(out + "/summary.json"), nullptr, false);
    run.eval = EvalJson(data + "_gt.tum", out + "/trajectory.tum", dir_);
    run.trajectory = ReadFile(out + "/trajectory.tum");
    return run;
  }
  std::string dir_;
};

double Metric(const RvRun& run, const char* group, const char* stat) {
  return run.eval[group][stat].get<double>();
}

// The tunnel preset as shipped (52 s, OS1-32 1024 columns). The defaults
// (gated reinforcement, repair up to eps1 0.03) beat RV off on ATE and
// along-axis RMSE and max on each of seeds 1-6 (docs/rv_modules.md "How the
// defaults were chosen", config/grids/rv_defaults.yaml: -6 to -23 % ATE);
// seed 3 is checked here because the paper's ungated modules lose to RV off
// on it (ATE 0.0228 vs 0.0199 m), so this test also guards the gate. No extra margin: the claim
// is "better", and the runs are deterministic.
TEST_F(RvCliTest, TunnelRvOnBeatsRvOffOnAteAndAlongAxisError) {
  Simulate("tunnel", 52, /*seed=*/3, /*columns=*/1024);
  const RvRun off = Run("tunnel", "off", "--set rv.enabled=false");
  const RvRun on = Run("tunnel", "on", "");
  ASSERT_FALSE(off.eval.is_null());
  ASSERT_FALSE(on.eval.is_null());
  const double scans = on.summary["scan_count"].get<double>();
  EXPECT_GE(on.summary["rv_active_scans"].get<double>(), 0.8 * scans);  // the tunnel is degenerate
  EXPECT_EQ(off.summary["rv_active_scans"].get<double>(), 0.0);
  EXPECT_LT(Metric(on, "ape", "rmse"), Metric(off, "ape", "rmse"));
  EXPECT_LT(Metric(on, "along_axis", "rmse"), Metric(off, "along_axis", "rmse"));
  EXPECT_LT(Metric(on, "along_axis", "max"), Metric(off, "along_axis", "max"));
  EXPECT_LT(Metric(on, "ape", "rmse"), 0.10);  // the target for RV-IESKF on the tunnel
}

TEST_F(RvCliTest, HallStaysInactiveAndKeepsItsAccuracy) {
  Simulate("hall", 20);
  const RvRun off = Run("hall", "off", "--set rv.enabled=false");
  const RvRun on = Run("hall", "on", "--set rv.enabled=true");
  ASSERT_FALSE(off.eval.is_null());
  ASSERT_FALSE(on.eval.is_null());
  const double scans = on.summary["scan_count"].get<double>();
  EXPECT_LE(on.summary["rv_active_scans"].get<double>(), 0.05 * scans);
  EXPECT_LE(on.eval["ape"]["rmse"].get<double>(), 1.05 * off.eval["ape"]["rmse"].get<double>());
  EXPECT_LT(on.eval["ape"]["rmse"].get<double>(), 0.05);
}

TEST_F(RvCliTest, FeaturelessActivatesOnNearlyEveryScanWithoutNaN) {
  Simulate("featureless", 20);
  const RvRun on = Run("featureless", "on", "--set rv.enabled=true");
  const double scans = on.summary["scan_count"].get<double>();
  ASSERT_GT(scans, 100);
  EXPECT_GE(on.summary["rv_active_scans"].get<double>(), 0.9 * scans);
  EXPECT_EQ(on.trajectory.find("nan"), std::string::npos);
  EXPECT_EQ(on.trajectory.find("inf"), std::string::npos);
  std::istringstream lines(on.trajectory);
  std::string line;
  int poses = 0;
  while (std::getline(lines, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    double v;
    while (fields >> v) ASSERT_TRUE(std::isfinite(v)) << line;
    ++poses;
  }
  EXPECT_EQ(poses, static_cast<int>(scans));
}

}  // namespace
}  // namespace rvlio

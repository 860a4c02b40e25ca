// `rvlio run` stopped by SIGINT / SIGTERM, a second signal and SIGKILL: what
// is written, compared with an uninterrupted run of the same bag.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "rvlio/formats/trajectory_io.h"
#include "signals_util.h"

namespace rvlio::signals_test {
namespace {

using nlohmann::json;
using testing_cli::MakeTempDir;
using testing_cli::RunTool;
using testing_cli::ToolRun;

const std::vector<std::string> kOutputs = {"map.pcd", "scans.csv", "summary.json",
                                           "trajectory.tum"};

// An 8 s, 512-column simulated tunnel and its uninterrupted run (dir_/full).
class RunSignalsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = MakeTempDir("rvlio_signals_run");
    ASSERT_FALSE(dir_.empty());
    const ToolRun sim = testing_cli::SimulateTunnel(dir_ + "/data", 4, 8, dir_);
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
    const ToolRun full = RunTool("run --quiet " + Args(dir_ + "/full"), dir_);
    ASSERT_EQ(full.exit_code, 0) << full.err;
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  static std::string Args(const std::string& out) {
    return "--bag " + dir_ + "/data/tunnel.bag --config " + dir_ + "/data/tunnel.yaml --out " + out;
  }
  static std::vector<std::string> ArgList(const std::string& out) {
    return {"run", "--quiet", "--bag", dir_ + "/data/tunnel.bag", "--config",
            dir_ + "/data/tunnel.yaml", "--out", out};
  }
  static std::vector<std::string> FullLines() {
    return CompleteLines(ReadFile(dir_ + "/full/trajectory.tum"));
  }
  // Starts a run into `out` and returns once trajectory.partial.tum has at
  // least `lines` poses (the run still going).
  static pid_t StartAndWaitForPoses(const std::string& out, int lines) {
    std::filesystem::create_directories(out);
    const pid_t pid = Spawn(ArgList(out), out + "/../stdout.txt", out + "/../stderr.txt");
    int status = -1;
    const bool ready = WaitUntil(
        pid, [&] { return CountLines(out + "/trajectory.partial.tum") >= lines + 1; }, &status);
    EXPECT_TRUE(ready) << "the run ended (status " << status << ") before " << lines << " poses";
    return pid;
  }
  static std::string Stderr(const std::string& out) { return ReadFile(out + "/../stderr.txt"); }

  // Interrupted outputs: complete, a prefix of the full run pose for pose
  // (the line lists hold the column comment line first).
  static void ExpectInterruptedOutputs(const std::string& out, const std::string& signal) {
    const std::vector<std::string> full = FullLines(), part = CompleteLines(ReadFile(out + "/trajectory.tum"));
    ASSERT_GE(part.size(), 4u);
    ASSERT_LT(part.size(), full.size());
    for (size_t i = 0; i < part.size(); ++i) ASSERT_EQ(part[i], full[i]) << "line " << i;
    const json s = json::parse(ReadFile(out + "/summary.json"), nullptr, false);
    ASSERT_TRUE(s.is_object());
    EXPECT_EQ(s["interrupted"], true);
    EXPECT_EQ(s["signal"], signal);
    EXPECT_EQ(s["scan_count"], part.size() - 1);
    StatusOr<Trajectory> t = ReadTum(out + "/trajectory.tum");
    ASSERT_TRUE(t.ok()) << t.status().message();
    EXPECT_NEAR(s["last_stamp_s"].get<double>(), NsToSeconds(t->back().t_ns), 1e-9);
    EXPECT_EQ(CountLines(out + "/scans.csv"), static_cast<int>(part.size()));  // both + header
    EXPECT_NE(ReadFile(out + "/map.pcd").find("\nDATA binary\n"), std::string::npos);
    // Nothing else: no partial trajectory, no staging folder.
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(out))
      names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, kOutputs);
  }

  static inline std::string dir_;
};

TEST_F(RunSignalsTest, UninterruptedRunRemovesThePartialTrajectory) {
  EXPECT_FALSE(Exists(dir_ + "/full/trajectory.partial.tum"));
  const json s = json::parse(ReadFile(dir_ + "/full/summary.json"));
  EXPECT_EQ(s["interrupted"], false);
  EXPECT_GT(FullLines().size(), 50u);
}

TEST_F(RunSignalsTest, SigintWritesThePrefixOfTheFullRunAndExits130) {
  const std::string out = dir_ + "/int/out";
  const pid_t pid = StartAndWaitForPoses(out, 3);
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  ASSERT_EQ(Wait(pid), 130) << Stderr(out);
  const std::string err = Stderr(out);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("rvlio run: interrupted by SIGINT after "), std::string::npos) << err;
  EXPECT_NE(err.find("wrote trajectory.tum, map.pcd, scans.csv and summary.json to " + out),
            std::string::npos) << err;
  ExpectInterruptedOutputs(out, "SIGINT");
}

TEST_F(RunSignalsTest, SigtermWritesThePrefixOfTheFullRunAndExits143) {
  const std::string out = dir_ + "/term/out";
  const pid_t pid = StartAndWaitForPoses(out, 5);
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  ASSERT_EQ(Wait(pid), 143) << Stderr(out);
  EXPECT_NE(Stderr(out).find("interrupted by SIGTERM"), std::string::npos) << Stderr(out);
  ExpectInterruptedOutputs(out, "SIGTERM");
}

// Two signals at once (both pending while the child is stopped): it aborts
// without writing, and the complete outputs of an earlier run stay as they were.
TEST_F(RunSignalsTest, SecondSignalAbortsAndKeepsEarlierOutputs) {
  const std::string out = dir_ + "/twice/out";
  std::filesystem::create_directories(out);
  for (const std::string& name : kOutputs)
    std::filesystem::copy_file(dir_ + "/full/" + name, out + "/" + name);
  const pid_t pid = StartAndWaitForPoses(out, 3);
  ASSERT_EQ(::kill(pid, SIGSTOP), 0);
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  ASSERT_EQ(::kill(pid, SIGCONT), 0);
  // 128 + whichever of the two came second (threads may take them at once).
  const int status = Wait(pid);
  EXPECT_TRUE(status == 130 || status == 143) << status;
  EXPECT_EQ(ReadFile(out + "/../stderr.txt"), "");  // no "interrupted ... wrote" line
  for (const std::string& name : kOutputs)
    EXPECT_EQ(ReadFile(out + "/" + name), ReadFile(dir_ + "/full/" + name)) << name;
  // What it estimated before the abort is in the partial trajectory.
  const std::vector<std::string> full = FullLines(),
                                 part = CompleteLines(ReadFile(out + "/trajectory.partial.tum"));
  ASSERT_GE(part.size(), 4u);
  for (size_t i = 0; i < part.size(); ++i) ASSERT_EQ(part[i], full[i]) << "line " << i;
  // The next run into that folder ends normally and removes what the abort left.
  const ToolRun again = RunTool("run --quiet " + Args(out), dir_);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(out))
    names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, kOutputs);
}

// SIGKILL: the partial trajectory holds whole lines only and is a valid TUM
// file, the prefix of the full run's trajectory.
TEST_F(RunSignalsTest, SigkillLeavesAParseablePartialTrajectory) {
  const std::string out = dir_ + "/kill/out";
  const pid_t pid = StartAndWaitForPoses(out, 4);
  ASSERT_EQ(::kill(pid, SIGKILL), 0);
  EXPECT_EQ(Wait(pid), 128 + SIGKILL);
  const std::string text = ReadFile(out + "/trajectory.partial.tum");
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');  // one write(2) per line: never a torn line
  StatusOr<Trajectory> t = ParseTumText(text, "trajectory.partial.tum");
  ASSERT_TRUE(t.ok()) << t.status().message();
  const std::vector<std::string> full = FullLines(), part = CompleteLines(text);
  ASSERT_GE(part.size(), 5u);
  ASSERT_LE(part.size(), full.size());
  for (size_t i = 0; i < part.size(); ++i) ASSERT_EQ(part[i], full[i]) << "line " << i;
  for (const std::string& name : kOutputs) EXPECT_FALSE(Exists(out + "/" + name)) << name;
}

// compare runs its variants in-process: the signal stops the running one,
// which keeps what it did; it and the steps not run are marked interrupted.
TEST_F(RunSignalsTest, InterruptedCompareTabulatesWhatItFinished) {
  const std::string out = dir_ + "/cmp";
  const pid_t pid = Spawn({"compare", "--bag", dir_ + "/data/tunnel.bag", "--gt",
                           dir_ + "/data/tunnel_gt.tum", "--config", dir_ + "/data/tunnel.yaml",
                           "--out", out, "--no-plots", "--quiet"},
                          dir_ + "/cmp_stdout.txt", dir_ + "/cmp_stderr.txt");
  const std::string second = out + "/ieskf_rv_on";
  int status = -1;
  const bool ready = WaitUntil(
      pid, [&] { return CountLines(second + "/trajectory.partial.tum") >= 4; }, &status);
  ASSERT_TRUE(ready) << "compare ended (status " << status << ") before its second variant";
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  ASSERT_EQ(Wait(pid), 130) << ReadFile(dir_ + "/cmp_stderr.txt");
  EXPECT_NE(ReadFile(dir_ + "/cmp_stderr.txt")
                .find("rvlio compare: interrupted by SIGINT: 1 of 5 steps finished"),
            std::string::npos) << ReadFile(dir_ + "/cmp_stderr.txt");
  const json j = json::parse(ReadFile(out + "/compare.json"), nullptr, false);
  ASSERT_TRUE(j.is_object());
  std::vector<std::string> statuses;
  for (const json& v : j["variants"]) statuses.push_back(v["status"]);
  EXPECT_EQ(statuses, (std::vector<std::string>{"ok", "interrupted", "interrupted",
                                                "interrupted", "interrupted"}));
  EXPECT_EQ(json::parse(ReadFile(second + "/summary.json"))["interrupted"], true);
  EXPECT_NE(ReadFile(out + "/compare.csv").find("ieskf_rv_on,\"IESKF, RV on (RV-LIO)\",interrupted,130"),
            std::string::npos);
  EXPECT_FALSE(Exists(out + "/smoother_rv_off"));
}

}  // namespace
}  // namespace rvlio::signals_test

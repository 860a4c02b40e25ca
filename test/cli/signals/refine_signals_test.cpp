// `rvlio refine` interrupted (the last completed round's result), killed and
// resumed from its checkpoint (byte for byte the uninterrupted result), and
// bad checkpoints.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "signals_util.h"

namespace rvlio::signals_test {
namespace {

using nlohmann::json;
using testing_cli::MakeTempDir;
using testing_cli::RunTool;
using testing_cli::ToolRun;

constexpr int kRounds = 3;

// A 6 s, 512-column simulated tunnel, its run (the initial trajectory) and
// the uninterrupted refinement of kRounds rounds (dir_/ref).
class RefineSignalsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = MakeTempDir("rvlio_signals_refine");
    ASSERT_FALSE(dir_.empty());
    const ToolRun sim = testing_cli::SimulateTunnel(dir_ + "/data", 6, 6, dir_);
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
    const ToolRun run = RunTool("run --quiet --bag " + Bag() + " --config " + Sensors() +
                                    " --out " + dir_ + "/run", dir_);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const ToolRun ref = Refine(dir_ + "/ref", kRounds, "--checkpoint " + dir_ + "/ref_ckpt");
    ASSERT_EQ(ref.exit_code, 0) << ref.err;
    const json s = Summary(dir_ + "/ref");
    ASSERT_EQ(s["rounds"].size(), static_cast<size_t>(kRounds)) << "converged early: no rounds to resume";
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  static std::string Bag() { return dir_ + "/data/tunnel.bag"; }
  static std::string Sensors() { return dir_ + "/data/tunnel.yaml"; }
  static std::vector<std::string> ArgList(const std::string& out, int rounds) {
    return {"refine", "--bag", Bag(), "--init", dir_ + "/run/trajectory.tum", "--config",
            Sensors(), "--set", "refine.rounds=" + std::to_string(rounds), "--out", out};
  }
  static ToolRun Refine(const std::string& out, int rounds, const std::string& extra = "") {
    std::string args;
    for (const std::string& a : ArgList(out, rounds)) args += a + " ";
    return RunTool(args + extra, dir_);
  }
  static json Summary(const std::string& out) {
    return json::parse(ReadFile(out + "/summary.json"), nullptr, false);
  }
  static void ExpectSameResult(const std::string& out, const std::string& reference) {
    for (const char* name : {"trajectory.tum", "map.pcd"}) {
      const std::string a = ReadFile(out + "/" + name), b = ReadFile(reference + "/" + name);
      ASSERT_FALSE(a.empty()) << out << "/" << name;
      EXPECT_TRUE(a == b) << name << " differs from " << reference;
    }
  }
  static int CheckpointRounds(const std::string& dir) {
    const std::string bytes = ReadFile(dir + "/refine.checkpoint");
    if (bytes.empty()) return -1;
    const json j = json::from_cbor(bytes, true, false);
    return j.is_object() ? j.value("rounds_done", -1) : -1;
  }

  static inline std::string dir_;
};

TEST_F(RefineSignalsTest, ResumeAfterFewerRoundsEqualsTheUninterruptedResult) {
  EXPECT_EQ(CheckpointRounds(dir_ + "/ref_ckpt"), kRounds);
  const ToolRun one = Refine(dir_ + "/one", 1, "--checkpoint " + dir_ + "/one_ckpt");
  ASSERT_EQ(one.exit_code, 0) << one.err;
  EXPECT_EQ(CheckpointRounds(dir_ + "/one_ckpt"), 1);
  const ToolRun resumed = Refine(dir_ + "/one_resumed", kRounds, "--resume " + dir_ + "/one_ckpt");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("resuming after round 1"), std::string::npos) << resumed.out;
  ExpectSameResult(dir_ + "/one_resumed", dir_ + "/ref");
  EXPECT_EQ(Summary(dir_ + "/one_resumed")["rounds"].size(), static_cast<size_t>(kRounds));
  EXPECT_EQ(CheckpointRounds(dir_ + "/one_ckpt"), kRounds);  // it goes on checkpointing there
}

TEST_F(RefineSignalsTest, KilledAfterARoundThenResumedEqualsTheUninterruptedResult) {
  const std::string ckpt = dir_ + "/kill_ckpt", out = dir_ + "/kill";
  std::vector<std::string> args = ArgList(out, kRounds);
  args.insert(args.end(), {"--checkpoint", ckpt});
  const pid_t pid = Spawn(args, dir_ + "/kill_stdout.txt", dir_ + "/kill_stderr.txt");
  int status = -1;
  const bool ready = WaitUntil(pid, [&] { return CheckpointRounds(ckpt) >= 1; }, &status);
  ::kill(pid, SIGKILL);
  Wait(pid);
  ASSERT_TRUE(ready) << "refine ended (status " << status << ") before its first round";
  const int done = CheckpointRounds(ckpt);
  ASSERT_GE(done, 1);
  const ToolRun resumed = Refine(out, kRounds, "--resume " + ckpt);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("resuming after round " + std::to_string(done)), std::string::npos)
      << resumed.out;
  ExpectSameResult(out, dir_ + "/ref");
}

// SIGINT after the first round line: the result of the last completed round,
// which is what a run with that many rounds gives.
TEST_F(RefineSignalsTest, SigintWritesTheLastCompletedRound) {
  const std::string out = dir_ + "/int";
  const pid_t pid = Spawn(ArgList(out, kRounds), dir_ + "/int_stdout.txt", dir_ + "/int_stderr.txt");
  int status = -1;
  const bool ready = WaitUntil(
      pid, [&] { return ReadFile(dir_ + "/int_stdout.txt").find("round 1/") != std::string::npos; },
      &status);
  ASSERT_TRUE(ready) << "refine ended (status " << status << ") before its first round";
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  ASSERT_EQ(Wait(pid), 130) << ReadFile(dir_ + "/int_stderr.txt");
  const std::string err = ReadFile(dir_ + "/int_stderr.txt");
  EXPECT_NE(err.find("rvlio refine: interrupted by SIGINT: wrote the result after round "),
            std::string::npos) << err;
  const json s = Summary(out);
  ASSERT_TRUE(s.is_object());
  EXPECT_EQ(s["interrupted"], true);
  EXPECT_EQ(s["signal"], "SIGINT");
  const int rounds = static_cast<int>(s["rounds"].size());
  ASSERT_GE(rounds, 1);
  if (rounds == kRounds) {
    ExpectSameResult(out, dir_ + "/ref");
  } else {
    const ToolRun same = Refine(dir_ + "/int_same", rounds);
    ASSERT_EQ(same.exit_code, 0) << same.err;
    ExpectSameResult(out, dir_ + "/int_same");
  }
}

TEST_F(RefineSignalsTest, BadCheckpointsAreRefusedInOneLine) {
  const std::string empty = dir_ + "/no_ckpt";
  std::filesystem::create_directories(empty);
  const ToolRun missing = Refine(dir_ + "/bad1", kRounds, "--resume " + empty);
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_EQ(std::count(missing.err.begin(), missing.err.end(), '\n'), 1) << missing.err;
  EXPECT_NE(missing.err.find("--resume " + empty + ": no checkpoint " + empty +
                             "/refine.checkpoint"), std::string::npos) << missing.err;
  EXPECT_FALSE(Exists(dir_ + "/bad1"));

  // Another configuration (or bag, or initial trajectory) than the checkpoint's.
  const ToolRun other = Refine(dir_ + "/bad2", kRounds,
                               "--set constraints.lidar_noise=0.05 --resume " + dir_ + "/ref_ckpt");
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_EQ(std::count(other.err.begin(), other.err.end(), '\n'), 1) << other.err;
  EXPECT_NE(other.err.find("was written for another bag, initial trajectory, --map or configuration"),
            std::string::npos) << other.err;
  EXPECT_FALSE(Exists(dir_ + "/bad2/trajectory.tum"));

  const std::string junk = dir_ + "/junk_ckpt";
  std::filesystem::create_directories(junk);
  std::ofstream(junk + "/refine.checkpoint") << "not a checkpoint";
  const ToolRun damaged = Refine(dir_ + "/bad3", kRounds, "--resume " + junk);
  EXPECT_EQ(damaged.exit_code, 2);
  EXPECT_NE(damaged.err.find("is not an rvlio refine checkpoint"), std::string::npos) << damaged.err;
}

}  // namespace
}  // namespace rvlio::signals_test

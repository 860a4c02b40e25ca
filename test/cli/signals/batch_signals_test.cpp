// `rvlio simulate` and `rvlio ablate` stopped by signals: never a half bag;
// finished ablation cells stay finished, the interrupted one runs again.
#include <filesystem>
#include <fstream>
#include <map>
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

class BatchSignalsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = MakeTempDir("rvlio_signals_batch");
    ASSERT_FALSE(dir_.empty());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // The size of the bag being written under `out` (simulate writes into a
  // staging folder inside it, formats/atomic_file.h); 0 while there is none.
  static uintmax_t BagBeingWritten(const std::string& out) {
    std::error_code ec;
    for (auto it = std::filesystem::recursive_directory_iterator(out, ec);
         !ec && it != std::filesystem::recursive_directory_iterator(); it.increment(ec))
      if (it->path().filename() == "tunnel.bag.tmp") {
        const uintmax_t size = std::filesystem::file_size(it->path(), ec);
        return ec ? 0 : size;
      }
    return 0;
  }

  // Starts a long simulation and returns once its bag is being written.
  pid_t StartSimulation(const std::string& out) {
    const pid_t pid = Spawn({"simulate", "--preset", "tunnel", "--duration", "120", "--out", out,
                             "--set", "lidar.columns=512"},
                            dir_ + "/stdout.txt", dir_ + "/stderr.txt");
    int status = -1;
    const bool ready = WaitUntil(
        pid,
        [&] { return BagBeingWritten(out) > 1000000; },
        &status);
    EXPECT_TRUE(ready) << "simulate ended (status " << status << ") before writing its bag";
    return pid;
  }

  std::string dir_;
};

std::vector<std::string> Entries(const std::string& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    names.push_back(e.path().filename().string());
  return names;
}

TEST_F(BatchSignalsTest, InterruptedSimulationLeavesNoBag) {
  const std::string out = dir_ + "/sim";
  const pid_t pid = StartSimulation(out);
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  EXPECT_EQ(Wait(pid), 130);
  EXPECT_EQ(ReadFile(dir_ + "/stderr.txt"), "rvlio simulate: interrupted by SIGINT; no bag written\n");
  EXPECT_TRUE(Entries(out).empty()) << Entries(out).front();
}

TEST_F(BatchSignalsTest, SimulationAbortedByASecondSignalLeavesNoBag) {
  const std::string out = dir_ + "/sim2";
  const pid_t pid = StartSimulation(out);
  ASSERT_EQ(::kill(pid, SIGSTOP), 0);
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  ASSERT_EQ(::kill(pid, SIGCONT), 0);
  const int status = Wait(pid);  // 128 + the second signal
  EXPECT_TRUE(status == 130 || status == 143) << status;
  EXPECT_TRUE(Entries(out).empty()) << Entries(out).front();
}

// Four cells of one 6 s tunnel, one at a time: SIGINT once the first is done.
TEST_F(BatchSignalsTest, InterruptedAblationKeepsFinishedCellsAndResumes) {
  const std::string grid = dir_ + "/grid.yaml", out = dir_ + "/out";
  std::ofstream(grid) << "sequences:\n  - name: tunnel\n    simulate:\n      preset: tunnel\n"
                         "      duration: 6\n      set:\n        lidar.columns: 512\n"
                         "    seeds: [1]\nvariants:\n  a: {rv.enabled: false}\n  b: {}\n"
                         "  c: {rv.k0: 3.0}\n  d: {rv.k0: 4.0}\n";
  const ToolRun plan_run = RunTool("ablate --grid " + grid + " --out " + out + " --plan", dir_);
  ASSERT_EQ(plan_run.exit_code, 0) << plan_run.err;
  const json plan = json::parse(plan_run.out);
  ASSERT_EQ(plan["cells"].size(), 4u);
  auto finished = [&] {
    int n = 0;
    for (const json& c : plan["cells"]) n += Exists(c["cell_json"].get<std::string>()) ? 1 : 0;
    return n;
  };
  const pid_t pid = Spawn({"ablate", "--grid", grid, "--out", out, "--jobs", "1", "--no-plots"},
                          dir_ + "/stdout.txt", dir_ + "/stderr.txt");
  int status = -1;
  const bool ready = WaitUntil(pid, [&] { return finished() >= 1; }, &status);
  ASSERT_TRUE(ready) << "ablate ended (status " << status << ") before its first cell";
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  ASSERT_EQ(Wait(pid), 130) << ReadFile(dir_ + "/stderr.txt");
  const std::string err = ReadFile(dir_ + "/stderr.txt");
  EXPECT_NE(err.find("rvlio ablate: interrupted by SIGINT: "), std::string::npos) << err;

  // Finished cells are complete; the others left nothing behind.
  std::map<std::string, std::string> kept;
  for (const json& c : plan["cells"]) {
    const std::string path = c["cell_json"];
    if (!Exists(path)) {
      EXPECT_FALSE(Exists(c["dir"].get<std::string>() + "/run")) << c["id"];
      continue;
    }
    const json r = json::parse(ReadFile(path));
    EXPECT_EQ(r["status"], "done") << r.dump();
    kept[path] = ReadFile(path);
  }
  ASSERT_GE(kept.size(), 1u);
  ASSERT_LT(kept.size(), 4u) << "every cell finished before the signal";

  const ToolRun again =
      RunTool("ablate --grid " + grid + " --out " + out + " --jobs 1 --no-plots --quiet", dir_);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find("4 cells: " + std::to_string(kept.size()) + " already done, " +
                           std::to_string(4 - kept.size()) + " run now"),
            std::string::npos) << again.out;
  for (const auto& [path, text] : kept) EXPECT_EQ(ReadFile(path), text) << path;
  EXPECT_EQ(finished(), 4);
}

}  // namespace
}  // namespace rvlio::signals_test

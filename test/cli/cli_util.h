#pragma once
// Helpers for end-to-end tests that run the built `rvlio` as a process.
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "rvlio/common/fnv1a.h"

namespace rvlio::testing_cli {

struct ToolRun {
  int exit_code = -1;
  std::string out, err;
};

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Runs `BIN ARGS` (BIN: the tool under test, RVLIO_BIN, unless given) with
// stdout/stderr captured into files under `scratch`.
inline ToolRun RunTool(const std::string& args, const std::string& scratch,
                       const std::string& bin = RVLIO_BIN) {
  const std::string out = scratch + "/stdout.txt", err = scratch + "/stderr.txt";
  const std::string cmd = bin + " " + args + " >" + out + " 2>" + err;
  const int status = std::system(cmd.c_str());
  ToolRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadFile(out);
  r.err = ReadFile(err);
  return r;
}

// Bad input: exit 2, exactly one stderr line "rvlio COMMAND: error: ..."
// containing `part`, nothing on stdout.
inline void ExpectOneErrorLine(const ToolRun& r, const std::string& command,
                               const std::string& part) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("rvlio " + command + ": error: ", 0), 0u) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "more than one line: " << r.err;
  EXPECT_NE(r.err.find(part), std::string::npos) << "'" << part << "' not in: " << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

// A CSV file with a header line of names (scans.csv, deviation.csv) as rows
// of named numbers; an empty or non-numeric field is NaN.
inline std::vector<std::map<std::string, double>> ReadCsv(const std::string& path) {
  std::istringstream in(ReadFile(path));
  std::string line;
  std::vector<std::string> names;
  if (std::getline(in, line)) {
    std::istringstream h(line);
    for (std::string n; std::getline(h, n, ',');) names.push_back(n);
  }
  std::vector<std::map<std::string, double>> rows;
  while (std::getline(in, line)) {
    std::istringstream f(line);
    std::map<std::string, double> row;
    std::string v;
    for (size_t i = 0; i < names.size(); ++i) {
      if (!std::getline(f, v, ',')) v.clear();
      char* end = nullptr;
      const double x = std::strtod(v.c_str(), &end);
      row[names[i]] = v.empty() || *end != '\0' ? NAN : x;
    }
    rows.push_back(row);
  }
  return rows;
}

inline std::string MakeTempDir(const std::string& stem) {
  std::string tmpl = std::filesystem::temp_directory_path().string() + "/" + stem + "_XXXXXX";
  if (::mkdtemp(tmpl.data()) == nullptr) return "";
  return tmpl;
}

// `rvlio eval --json` of an estimate against ground truth.
inline nlohmann::json EvalJson(const std::string& gt, const std::string& est,
                               const std::string& scratch) {
  const ToolRun r = RunTool("eval --gt " + gt + " --est " + est + " --json", scratch);
  if (r.exit_code != 0) return nlohmann::json();
  return nlohmann::json::parse(r.out, nullptr, false);
}

// ATE (m) of an estimate against ground truth in the ground truth's frame
// (`eval --align none`: a run localized in a reference map); NaN on failure.
inline double AteNoAlign(const std::string& gt, const std::string& est, const std::string& scratch) {
  const ToolRun r = RunTool("eval --gt " + gt + " --est " + est + " --align none --json", scratch);
  if (r.exit_code != 0) return NAN;
  const nlohmann::json j = nlohmann::json::parse(r.out, nullptr, false);
  return j.is_discarded() ? NAN : j["ape"]["rmse"].get<double>();
}


// The tool CachedSimulate simulates with: $RVLIO_TEST_SIM_BIN, else the tool
// under test. The sanitize stage (scripts/sanitize.sh) points it at the
// Release stage's tool and cache: its simulations are the Release stage's
// (the simulator's own code runs under the sanitizers in test_sim and in the
// tests that call `simulate` themselves), and the tool under test reads them.
inline std::string SimulatorBin() {
  const char* env = std::getenv("RVLIO_TEST_SIM_BIN");
  return env != nullptr && *env != '\0' ? env : RVLIO_BIN;
}

// Where CachedSimulate keeps its simulations: $RVLIO_TEST_CACHE, else
// test-sim-cache/ next to the simulating tool's bin/ folder.
inline std::filesystem::path SimulationCacheDir() {
  if (const char* env = std::getenv("RVLIO_TEST_CACHE"); env != nullptr && *env != '\0') return env;
  return std::filesystem::path(SimulatorBin()).parent_path().parent_path() / "test-sim-cache";
}

// The cache key of a simulation: FNV-1a over the simulate arguments and the
// size and modification time of the simulating tool, so a rebuilt simulator
// simulates again.
inline std::string SimulationKey(const std::string& sim_args) {
  struct stat st {};
  const std::string text = sim_args + "|" +
                           (::stat(SimulatorBin().c_str(), &st) == 0
                                ? std::to_string(st.st_size) + ":" + std::to_string(st.st_mtime)
                                : std::string("?"));
  return Fnv1aHex(text);
}

// `rvlio simulate SIM_ARGS --out OUT`, simulated once per build and copied
// from the cache afterwards. gtest_discover_tests runs every test case in its
// own process, so a suite's SetUpTestSuite simulation would otherwise run
// once per case. A successful simulation is written into a private folder and
// renamed into the cache (concurrent test processes race safely: the first
// rename wins, the others use it); a failed one is returned as it is and not
// cached. The files are copied, so a test may corrupt its copy.
inline ToolRun CachedSimulate(const std::string& sim_args, const std::string& out,
                              const std::string& scratch) {
  namespace fs = std::filesystem;
  const fs::path cache = SimulationCacheDir(), entry = cache / SimulationKey(sim_args);
  std::error_code ec;
  if (!fs::exists(entry / "stdout.txt")) {
    fs::create_directories(cache, ec);
    std::string tmpl = (cache / ("tmp_XXXXXX")).string();
    if (::mkdtemp(tmpl.data()) == nullptr)
      return RunTool("simulate " + sim_args + " --out " + out, scratch, SimulatorBin());
    const ToolRun sim =
        RunTool("simulate " + sim_args + " --out " + tmpl + "/out", tmpl, SimulatorBin());
    if (sim.exit_code != 0) {
      fs::remove_all(tmpl, ec);
      return sim;
    }
    fs::rename(tmpl, entry, ec);  // fails when another process was first
    if (ec) fs::remove_all(tmpl, ec);
  }
  ToolRun r;
  fs::create_directories(out, ec);
  fs::copy(entry / "out", out, fs::copy_options::recursive | fs::copy_options::overwrite_existing, ec);
  if (ec) {
    r.err = "copying the cached simulation " + entry.string() + " to " + out + ": " + ec.message();
    return r;
  }
  r.exit_code = 0;
  r.out = ReadFile((entry / "stdout.txt").string());
  r.err = ReadFile((entry / "stderr.txt").string());
  return r;
}

// Simulates a 10 s, 512-column hall without sensor noise, wall roughness or
// IMU biases into `dir` (hall.bag, hall.yaml, hall_gt.tum): the oracle case.
// Cached (CachedSimulate).
inline ToolRun SimulateNoiseFreeHall(const std::string& dir) {
  return CachedSimulate("--preset hall --seed 5 --duration 10"
                        " --set lidar.columns=512 --set lidar.range_noise=0"
                        " --set world.roughness_amplitude=0"
                        " --set imu.gyro_noise_density=0 --set imu.accel_noise_density=0"
                        " --set imu.gyro_bias_random_walk=0 --set imu.accel_bias_random_walk=0"
                        " --set imu.gyro_bias=[0,0,0] --set imu.accel_bias=[0,0,0]",
                        dir, dir);
}

// `rvlio simulate --preset tunnel` of `duration_s` seconds, 512 columns, seed
// `seed`, into `out` (tunnel.bag, tunnel.yaml, tunnel_gt.tum unless `extra`
// renames or reformats them); `extra` holds further simulate arguments.
// Cached (CachedSimulate); `scratch` receives the tool's output on a miss.
inline ToolRun SimulateTunnel(const std::string& out, int seed, int duration_s,
                              const std::string& scratch, const std::string& extra = "") {
  return CachedSimulate("--preset tunnel --seed " + std::to_string(seed) + " --duration " +
                            std::to_string(duration_s) + " --set lidar.columns=512" +
                            (extra.empty() ? "" : " " + extra),
                        out, scratch);
}

// A suite sharing one seeded 14 s, 512-column simulated tunnel (tunnel.bag,
// tunnel.yaml, tunnel_gt.tum under dir_/data), made once per suite.
class SimulatedTunnelSuite : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = MakeTempDir("rvlio_cli");
    ASSERT_FALSE(dir_.empty());
    const ToolRun sim = SimulateTunnel(dir_ + "/data", 3, 14, dir_);
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  static std::string Bag() { return dir_ + "/data/tunnel.bag"; }
  static std::string Sensors() { return dir_ + "/data/tunnel.yaml"; }
  static std::string Truth() { return dir_ + "/data/tunnel_gt.tum"; }
  // `rvlio run` on the suite's bag with its sensor configuration.
  static ToolRun Run(const std::string& out, const std::string& extra = "") {
    return RunTool("run --bag " + Bag() + " --config " + Sensors() + " --out " + out + " " + extra,
                   dir_);
  }
  static inline std::string dir_;
};

// SimulatedTunnelSuite plus an IESKF run of its bag (dir_/ieskf): the
// initial trajectory of the refine suites.
class IeskfTunnelSuite : public SimulatedTunnelSuite {
 protected:
  static void SetUpTestSuite() {
    SimulatedTunnelSuite::SetUpTestSuite();
    if (::testing::Test::HasFatalFailure()) return;
    const ToolRun run = Run(dir_ + "/ieskf", "--set backend=ieskf");
    ASSERT_EQ(run.exit_code, 0) << run.err;
  }
  static std::string Init() { return dir_ + "/ieskf/trajectory.tum"; }
};

}  // namespace rvlio::testing_cli

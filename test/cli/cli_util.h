#pragma once
// Helpers for end-to-end tests that run the built `rvlio` as a process.
#include <stdlib.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace rvlio::testing_cli {

struct ToolRun {
  int exit_code = -1;
  std::string out, err;
};

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Runs `rvlio ARGS` with stdout/stderr captured into files under `scratch`.
inline ToolRun RunTool(const std::string& args, const std::string& scratch) {
  const std::string out = scratch + "/stdout.txt", err = scratch + "/stderr.txt";
  const std::string cmd = std::string(RVLIO_BIN) + " " + args + " >" + out + " 2>" + err;
  const int status = std::system(cmd.c_str());
  ToolRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadFile(out);
  r.err = ReadFile(err);
  return r;
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

// Simulates a 10 s, 512-column hall without sensor noise, wall roughness or
// IMU biases into `dir` (hall.bag, hall.yaml, hall_gt.tum): the oracle case.
inline ToolRun SimulateNoiseFreeHall(const std::string& dir) {
  return RunTool("simulate --preset hall --seed 5 --duration 10 --out " + dir +
                     " --set lidar.columns=512 --set lidar.range_noise=0"
                     " --set world.roughness_amplitude=0"
                     " --set imu.gyro_noise_density=0 --set imu.accel_noise_density=0"
                     " --set imu.gyro_bias_random_walk=0 --set imu.accel_bias_random_walk=0"
                     " --set imu.gyro_bias=[0,0,0] --set imu.accel_bias=[0,0,0]",
                 dir);
}

// `rvlio simulate --preset tunnel` of `duration_s` seconds, 512 columns, seed
// `seed`, into `out` (tunnel.bag, tunnel.yaml, tunnel_gt.tum unless `extra`
// renames or reformats them); `extra` holds further simulate arguments.
inline ToolRun SimulateTunnel(const std::string& out, int seed, int duration_s,
                              const std::string& scratch, const std::string& extra = "") {
  return RunTool("simulate --preset tunnel --seed " + std::to_string(seed) + " --duration " +
                     std::to_string(duration_s) + " --set lidar.columns=512 --out " + out +
                     (extra.empty() ? "" : " " + extra),
                 scratch);
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

}  // namespace rvlio::testing_cli

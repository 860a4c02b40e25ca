// End to end: the LiDAR-IMU time offset (docs/time_offset.md) on seeded
// simulated flights with carried-sensor sway (512 columns):
//   - `rvlio simulate --set lidar.time_offset=` writes shifted LiDAR stamps and
//     keeps the offset out of the configuration it writes;
//   - online estimation, both backends, on a +30 ms bag: the estimate within
//     2 ms of the truth once excited, ATE within 20 % of the synchronized run;
//   - estimation on with synchronized clocks: ATE at most 10 % worse (target 5 %);
//   - `rvlio calibrate-time` finds the offset within 3 ms, and says "not
//     enough rotation" on a flight that never turns;
//   - a drifting clock offset: both backends follow the drift;
//   - a 100 ms clock error without estimation stops the run (exit 3) with a
//     message naming the clocks and the check command.
// Short flights (TimeOffsetShortFlights, 8 s and 2 s): calibrate-time within
// 2 sigma where it was biased, "too short to judge" on 2 s, and an estimate
// beyond its bound that keeps the stamps increasing.
// The full matrix (-100/-30/+30/+100 ms, tunnel and hall, both backends) is
// TimeOffsetMatrix (Release stage only: excluded from the sanitizer stage).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_util.h"

namespace rvlio {
namespace {

using testing_cli::CachedSimulate;
using testing_cli::EvalJson;
using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

// Sway ("normal excitation" of docs/extrinsics.md) makes the offset observable.
constexpr const char* kSway = " --set trajectory.sway_amplitude=0.1 --set trajectory.sway_frequency=1";

std::string SimArgs(const std::string& preset, int duration_s, double offset_s) {
  std::ostringstream a;
  a << "--preset " << preset << " --seed 3 --duration " << duration_s
    << " --set lidar.columns=512" << kSway;
  if (offset_s != 0.0) a << " --set lidar.time_offset=" << offset_s;
  return a.str();
}

// The cells of one CSV line (scans.csv quotes nothing).
std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> cells;
  std::istringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
  return cells;
}

// The stamps of a trajectory.tum (comments skipped).
std::vector<double> TumStamps(const std::string& out) {
  std::istringstream in(ReadFile(out + "/trajectory.tum"));
  std::vector<double> stamps;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') stamps.push_back(std::stod(line));
  return stamps;
}

class TimeOffsetCliTest : public ::testing::Test {
 protected:
  static constexpr double kOffsetS = 0.03;
  static constexpr int kDurationS = 20;
  static void SetUpTestSuite() {
    dir_ = testing_cli::MakeTempDir("rvlio_toff");
    ASSERT_FALSE(dir_.empty());
    using Bag = std::pair<std::string, double>;
    for (const Bag& bag : {Bag{"sync", 0.0}, Bag{"off30", kOffsetS}}) {
      const auto& [name, offset] = bag;
      const ToolRun sim =
          CachedSimulate(SimArgs("tunnel", kDurationS, offset), dir_ + "/" + name, dir_);
      ASSERT_EQ(sim.exit_code, 0) << sim.err;
    }
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  static ToolRun Run(const std::string& bag, const std::string& out, const std::string& extra) {
    return RunTool("run --bag " + dir_ + "/" + bag + "/tunnel.bag --config " + dir_ + "/" + bag +
                       "/tunnel.yaml --out " + out + " --quiet " + extra,
                   dir_);
  }
  static double Ate(const std::string& bag, const std::string& out) {
    const auto j = EvalJson(dir_ + "/" + bag + "/tunnel_gt.tum", out + "/trajectory.tum", dir_);
    return j.is_null() ? 1e9 : j["ape"]["rmse"].get<double>();
  }
  static nlohmann::json TimeOffset(const std::string& out) {
    return nlohmann::json::parse(ReadFile(out + "/summary.json"))["time_offset"];
  }
  // The estimate on the +30 ms bag and the ATE against the synchronized run.
  static void ExpectRecovered(const std::string& backend) {
    const std::string sync = dir_ + "/" + backend + "_sync", est = dir_ + "/" + backend + "_est";
    ASSERT_EQ(Run("sync", sync, "--set backend=" + backend).exit_code, 0);
    const ToolRun r =
        Run("off30", est, "--set backend=" + backend + " --set lidar.estimate_time_offset=true");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json t = TimeOffset(est);
    ASSERT_TRUE(t.is_object());
    EXPECT_TRUE(t["excited"].get<bool>()) << t.dump();
    EXPECT_NEAR(t["estimate_s"].get<double>(), kOffsetS, 0.002) << t.dump();
    const double ate_sync = Ate("sync", sync), ate_est = Ate("off30", est);
    EXPECT_LT(ate_est, 1.2 * ate_sync) << backend << ": " << ate_sync << " -> " << ate_est;
    // scans.csv follows the estimate.
    const std::string csv = ReadFile(est + "/scans.csv");
    EXPECT_NE(csv.substr(0, csv.find('\n')).find(",time_offset_s,time_offset_std_s"),
              std::string::npos);
  }
  static inline std::string dir_;
};

// Short flights (8 s and less) of their own, without the suite's 20 s ones.
class TimeOffsetShortFlights : public ::testing::Test {
 protected:
  static constexpr double kOffsetS = 0.03;
  static void SetUpTestSuite() {
    dir_ = testing_cli::MakeTempDir("rvlio_toff_short");
    ASSERT_FALSE(dir_.empty());
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }
  static nlohmann::json TimeOffset(const std::string& out) {
    return nlohmann::json::parse(ReadFile(out + "/summary.json"))["time_offset"];
  }
  static inline std::string dir_;
};

TEST_F(TimeOffsetCliTest, SimulateKeepsTheClockOffsetOutOfTheConfiguration) {
  std::istringstream yaml(ReadFile(dir_ + "/off30/tunnel.yaml"));
  for (std::string line; std::getline(yaml, line);)
    if (line.find("time_offset") != std::string::npos) {
      EXPECT_EQ(line.rfind('#', 0), 0u) << line;
    }
  EXPECT_NE(ReadFile(dir_ + "/off30/tunnel.bag"), ReadFile(dir_ + "/sync/tunnel.bag"));
}

TEST_F(TimeOffsetCliTest, IeskfEstimatesA30MsOffset) { ExpectRecovered("ieskf"); }

TEST_F(TimeOffsetCliTest, SmootherEstimatesA30MsOffset) { ExpectRecovered("smoother"); }

TEST_F(TimeOffsetCliTest, EstimationWithSynchronizedClocksKeepsTheAccuracy) {
  const std::string off = dir_ + "/zero_off", on = dir_ + "/zero_on";
  ASSERT_EQ(Run("sync", off, "--set backend=ieskf").exit_code, 0);
  ASSERT_EQ(Run("sync", on, "--set backend=ieskf --set lidar.estimate_time_offset=true").exit_code,
            0);
  // The target, 5 %: with the replay, over seeds 3 to 13 of the tunnel and
  // the hall the measured ratio is 0.97 to 1.03, this seed's 1.02
  // (docs/time_offset.md).
  EXPECT_LT(Ate("sync", on), 1.05 * Ate("sync", off));
  EXPECT_NEAR(TimeOffset(on)["estimate_s"].get<double>(), 0.0, 0.002);
}

// The IESKF map hold (lidar.time_offset_map_hold), without the replay
// (time_offset_replay 0): on the +30 ms bag the first moving scans are
// provisional until the offset converges (about 0.5 s of motion at 10 Hz:
// between 1 and 10 scans), the estimate is as accurate and the ATE within
// 20 % of the synchronized run (measured 1.02, docs/time_offset.md "Map
// hold"). Off by default: no provisional scans. With the replay the hold
// ends at the first replayed scan (the offset converged): none either.
TEST_F(TimeOffsetCliTest, IeskfMapHoldKeepsTheAccuracy) {
  const std::string sync = dir_ + "/hold_sync", off = dir_ + "/hold_off", on = dir_ + "/hold_on";
  const std::string replayed = dir_ + "/hold_replayed";
  ASSERT_EQ(Run("sync", sync, "--set backend=ieskf").exit_code, 0);
  const std::string est = "--set backend=ieskf --set lidar.estimate_time_offset=true";
  const std::string hold = " --set lidar.time_offset_map_hold=1";
  ASSERT_EQ(Run("off30", off, est + " --set lidar.time_offset_replay=0").exit_code, 0);
  const ToolRun r = Run("off30", on, est + hold + " --set lidar.time_offset_replay=0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(Run("off30", replayed, est + hold).exit_code, 0);
  EXPECT_EQ(TimeOffset(off)["map_hold_scans"].get<int>(), 0);
  EXPECT_EQ(TimeOffset(replayed)["map_hold_scans"].get<int>(), 0);
  const nlohmann::json t = TimeOffset(on);
  EXPECT_GE(t["map_hold_scans"].get<int>(), 1) << t.dump();
  EXPECT_LE(t["map_hold_scans"].get<int>(), 10) << t.dump();
  EXPECT_NEAR(t["estimate_s"].get<double>(), kOffsetS, 0.002) << t.dump();
  EXPECT_LT(Ate("off30", on), 1.2 * Ate("sync", sync));
}

// The IESKF replay (lidar.time_offset_replay, on by default): on the +30 ms
// bag the scans from the start of the motion to the offset's convergence
// (about 0.5 s at 10 Hz) are processed again with the converged offset;
// every scan's pose is written once, in increasing time, as many as without
// the replay (the shift moves no scan before the state at +30 ms).
TEST_F(TimeOffsetCliTest, IeskfReplayEmitsEachScanOnceInOrder) {
  const std::string est = "--set backend=ieskf --set lidar.estimate_time_offset=true";
  const std::string on = dir_ + "/replay_on", off = dir_ + "/replay_off";
  ASSERT_EQ(Run("off30", on, est).exit_code, 0);
  ASSERT_EQ(Run("off30", off, est + " --set lidar.time_offset_replay=0").exit_code, 0);
  const nlohmann::json t = TimeOffset(on);
  EXPECT_GE(t["replayed_scans"].get<int>(), 1) << t.dump();
  EXPECT_LE(t["replayed_scans"].get<int>(), 20) << t.dump();
  EXPECT_EQ(TimeOffset(off)["replayed_scans"].get<int>(), 0);
  const std::vector<double> stamps_on = TumStamps(on), stamps_off = TumStamps(off);
  EXPECT_EQ(stamps_on.size(), stamps_off.size());
  for (size_t i = 1; i < stamps_on.size(); ++i) EXPECT_GT(stamps_on[i], stamps_on[i - 1]) << i;
}

// A hold that ends without replay leaves the results as they were: holds
// that never converge (time_offset_replay_std 1e-7 s; each given up after one
// scan, time_offset_replay 0.05 s, then a new one starts, three in all) and the end of input
// inside the hold (--duration 3.6: four scans of motion, the offset's 1-sigma
// still 1.9 ms, above lidar.time_offset_replay_std) write the trajectory of
// the run without the replay, byte for byte.
TEST_F(TimeOffsetCliTest, IeskfReplayGiveUpKeepsTheResults) {
  const std::string est = "--set backend=ieskf --set lidar.estimate_time_offset=true";
  const std::string off = dir_ + "/giveup_off", early = dir_ + "/giveup_early";
  ASSERT_EQ(Run("off30", off, est + " --set lidar.time_offset_replay=0").exit_code, 0);
  ASSERT_EQ(Run("off30", early, est + " --set lidar.time_offset_replay=0.05 --set lidar.time_offset_replay_std=1e-7")
                .exit_code, 0);
  EXPECT_EQ(TimeOffset(early)["replayed_scans"].get<int>(), 0);
  EXPECT_EQ(ReadFile(early + "/trajectory.tum"), ReadFile(off + "/trajectory.tum"));
  const std::string cut_off = dir_ + "/finish_off", cut_on = dir_ + "/finish_on";
  const std::string cut = est + " --duration 3.6";
  ASSERT_EQ(Run("off30", cut_off, cut + " --set lidar.time_offset_replay=0").exit_code, 0);
  ASSERT_EQ(Run("off30", cut_on, cut).exit_code, 0);
  EXPECT_EQ(TimeOffset(cut_on)["replayed_scans"].get<int>(), 0);
  EXPECT_EQ(ReadFile(cut_on + "/trajectory.tum"), ReadFile(cut_off + "/trajectory.tum"));
  EXPECT_GT(TumStamps(cut_on).size(), 20u);
}

// A drifting LiDAR clock (simulator lidar.time_offset_drift, 200 ppm: the
// offset grows from 30 to 34 ms over the 20 s flight): both backends follow it
// (the IESKF through the offset's random walk, the smoother through its
// random walk between windows). Every scan from 6 s on (after the start-up
// transient) within 0.6 ms of the true offset at its time, which a constant
// estimate (4 ms of drift) cannot meet.
TEST_F(TimeOffsetCliTest, EstimateFollowsADriftingOffset) {
  constexpr double kDrift = 2e-4;  // s/s
  const ToolRun sim = CachedSimulate(SimArgs("tunnel", kDurationS, kOffsetS) +
                                         " --set lidar.time_offset_drift=" + std::to_string(kDrift),
                                     dir_ + "/drift", dir_);
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  // The simulated flight starts at the first ground-truth stamp.
  std::istringstream gt(ReadFile(dir_ + "/drift/tunnel_gt.tum"));
  std::string line;
  while (std::getline(gt, line) && line.rfind('#', 0) == 0) {
  }
  const double t_start = std::stod(line);
  for (const std::string backend : {"ieskf", "smoother"}) {
    const std::string out = dir_ + "/drift_" + backend;
    const ToolRun r =
        Run("drift", out, "--set backend=" + backend + " --set lidar.estimate_time_offset=true");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::istringstream csv(ReadFile(out + "/scans.csv"));
    std::getline(csv, line);
    const std::vector<std::string> header = SplitCsvLine(line);
    const auto column = [&header](const std::string& name) {
      return std::find(header.begin(), header.end(), name) - header.begin();
    };
    const size_t t_col = column("t"), td_col = column("time_offset_s");
    ASSERT_LT(td_col, header.size());
    int checked = 0;
    while (std::getline(csv, line)) {
      const std::vector<std::string> f = SplitCsvLine(line);
      const double t_s = std::stod(f[t_col]) - t_start;
      if (t_s < 6.0) continue;
      const double truth_s = kOffsetS + kDrift * t_s;
      EXPECT_NEAR(std::stod(f[td_col]), truth_s, 6e-4) << backend << " at " << t_s << " s";
      ++checked;
    }
    EXPECT_GT(checked, 100) << backend;
  }
}

// The offset printed by `rvlio calibrate-time` ("offset: X s").
double PrintedOffset(const std::string& out) {
  const size_t at = out.find("offset: ");
  if (at == std::string::npos) return 1e9;
  return std::stod(out.substr(at + 8));
}

TEST_F(TimeOffsetCliTest, CalibrateTimeFindsTheOffset) {
  const ToolRun r = RunTool("calibrate-time --bag " + dir_ + "/off30/tunnel.bag --config " + dir_ +
                                "/off30/tunnel.yaml",
                            dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NEAR(PrintedOffset(r.out), kOffsetS, 0.003) << r.out;
  EXPECT_NE(r.out.find("header stamp marks the scan start"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(", 0 dropped"), std::string::npos) << r.out;
}

TEST_F(TimeOffsetCliTest, CalibrateTimeSaysNotEnoughRotationOnAFlightThatNeverTurns) {
  const std::string out = dir_ + "/straight";
  const ToolRun sim = CachedSimulate(
      "--preset tunnel --seed 3 --duration 12 --set lidar.columns=512"
      " --set trajectory.yaw_amplitude=0 --set trajectory.waypoints='0,0,0; 0,0,3'"
      " --set lidar.time_offset=0.03",
      out, dir_);
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const ToolRun r = RunTool(
      "calibrate-time --bag " + out + "/tunnel.bag --config " + out + "/tunnel.yaml", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("not enough rotation"), std::string::npos) << r.out;
}

// The 1-sigma printed by `rvlio calibrate-time` ("1-sigma X ms"), s.
double PrintedStd(const std::string& out) {
  const size_t at = out.find("1-sigma ");
  if (at == std::string::npos) return 0.0;
  return 1e-3 * std::stod(out.substr(at + 8));
}

// Item: on a short swaying flight (8 s, the first 3 s at rest) calibrate-time
// was biased by -6 ms (23.9 +- 1.59 ms for 30 ms; -6.1 ms on the synchronized
// copy): it took each scan-to-scan rotation as the rate between the scans'
// mid-times, while the points that carry the registration see other times.
// Its error is now within 2 sigma and 1.5 ms (so with the right offset
// configured it would not call the clocks unsynchronized: that needs a lag
// over 2 ms and 3 sigma).
TEST_F(TimeOffsetShortFlights, CalibrateTimeOnAShortSwayingFlightIsUnbiased) {
  const std::string out = dir_ + "/short8";
  const ToolRun sim = CachedSimulate(SimArgs("tunnel", 8, kOffsetS), out, dir_);
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const ToolRun r = RunTool(
      "calibrate-time --bag " + out + "/tunnel.bag --config " + out + "/tunnel.yaml", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double offset_s = PrintedOffset(r.out), std_s = PrintedStd(r.out);
  EXPECT_NEAR(offset_s, kOffsetS, 0.0015) << r.out;
  EXPECT_LE(std::abs(offset_s - kOffsetS), 2.0 * std_s) << r.out;
}

// Item: a recording too short to judge (2 s of swaying flight) gets no
// recommended offset, and the line says why.
TEST_F(TimeOffsetShortFlights, CalibrateTimeSaysWhenARecordingIsTooShort) {
  const std::string out = dir_ + "/short2";
  const ToolRun sim = CachedSimulate(
      SimArgs("tunnel", 2, kOffsetS) + " --set trajectory.static_duration=0", out, dir_);
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const ToolRun r = RunTool(
      "calibrate-time --bag " + out + "/tunnel.bag --config " + out + "/tunnel.yaml", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("too short to judge"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("set lidar.time_offset"), std::string::npos) << r.out;
}

// Item: 1 s of clock offset, twice lidar.time_offset_max (0.2 s) ahead of
// what the estimate may reach: the IESKF's estimate swings between the
// bounds from scan to scan, and a scan moved by a lower estimate than the
// one before it was estimated behind it: trajectory.tum's stamps went back
// (and eval refused it). Such a scan is skipped now (scans_out_of_order);
// summary.json's at_bound and estimate_s and the warning say the same.
TEST_F(TimeOffsetShortFlights, EstimateBeyondTheBoundKeepsStampsIncreasing) {
  const std::string sim_out = dir_ + "/off1000";
  const ToolRun sim = CachedSimulate(SimArgs("tunnel", 8, 1.0), sim_out, dir_);
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const std::string out = dir_ + "/off1000_run";
  const ToolRun r = RunTool("run --bag " + sim_out + "/tunnel.bag --config " + sim_out +
                                "/tunnel.yaml --out " + out +
                                " --quiet --allow-divergence --set lidar.estimate_time_offset=true",
                            dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<double> t = TumStamps(out);
  ASSERT_GT(t.size(), 10u);
  for (size_t i = 1; i < t.size(); ++i) EXPECT_LT(t[i - 1], t[i]) << "pose " << i;
  const nlohmann::json td = TimeOffset(out);
  ASSERT_GT(td["bound_scans"].get<int>(), 0) << td.dump();
  char final_text[64];
  if (td["at_bound"].get<bool>()) {
    EXPECT_DOUBLE_EQ(std::abs(td["estimate_s"].get<double>()), td["bound_s"].get<double>());
    std::snprintf(final_text, sizeof(final_text), "is held at lidar.time_offset_max (%+g s)",
                  td["estimate_s"].get<double>());
  } else {
    std::snprintf(final_text, sizeof(final_text), "and ended at %.4f s",
                  td["estimate_s"].get<double>());
  }
  EXPECT_NE(r.err.find(final_text), std::string::npos) << final_text << "\n" << r.err;
  EXPECT_NE(td["note"].get<std::string>().find(final_text), std::string::npos) << td.dump();
  EXPECT_FALSE(td["trustworthy"].get<bool>());
  EXPECT_EQ(EvalJson(sim_out + "/tunnel_gt.tum", out + "/trajectory.tum", dir_).is_null(), false);
}

// 30 ms of true offset configured as -70 ms: 100 ms of clock error.
TEST_F(TimeOffsetCliTest, DivergenceFromUnsynchronizedClocksNamesTheCheck) {
  const ToolRun r = Run("off30", dir_ + "/wrong", "--set backend=ieskf --set lidar.time_offset=-0.07");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("rvlio calibrate-time"), std::string::npos) << r.err;
}

// The full matrix: per (preset, backend), the synchronized run and one
// estimation run per offset. Release stage only (scripts/sanitize.sh
// excludes it); the table of docs/time_offset.md comes from these runs.
class TimeOffsetMatrix : public ::testing::TestWithParam<std::pair<std::string, std::string>> {};

TEST_P(TimeOffsetMatrix, EstimatesEveryOffsetAndKeepsTheAccuracy) {
  const auto& [preset, backend] = GetParam();
  const std::string dir = testing_cli::MakeTempDir("rvlio_toff_matrix");
  ASSERT_FALSE(dir.empty());
  constexpr int kDurationS = 20;
  auto simulate_and_run = [&](double offset_s, const std::string& extra, double* ate) {
    std::ostringstream name;
    name << dir << "/" << preset << "_" << std::lround(offset_s * 1000);
    const ToolRun sim = CachedSimulate(SimArgs(preset, kDurationS, offset_s), name.str(), dir);
    if (sim.exit_code != 0) return nlohmann::json();
    const std::string out = name.str() + "/out";
    const ToolRun r = RunTool("run --bag " + name.str() + "/" + preset + ".bag --config " +
                                  name.str() + "/" + preset + ".yaml --out " + out +
                                  " --quiet --set backend=" + backend + " " + extra,
                              dir);
    if (r.exit_code != 0) return nlohmann::json();
    const auto j = EvalJson(name.str() + "/" + preset + "_gt.tum", out + "/trajectory.tum", dir);
    *ate = j.is_null() ? 1e9 : j["ape"]["rmse"].get<double>();
    return nlohmann::json::parse(ReadFile(out + "/summary.json"));
  };
  double ate_sync = 0.0;
  ASSERT_TRUE(simulate_and_run(0.0, "", &ate_sync).is_object());
  for (double offset_s : {-0.1, -0.03, 0.03, 0.1}) {
    double ate = 0.0;
    const nlohmann::json s =
        simulate_and_run(offset_s, "--set lidar.estimate_time_offset=true", &ate);
    ASSERT_TRUE(s.is_object()) << preset << " " << backend << " " << offset_s;
    const nlohmann::json& t = s["time_offset"];
    std::printf("%s %s offset %+.3f s: estimate %+.4f s (1-sigma %.4f, excited %d), ATE %.4f m "
                "(synchronized %.4f m)\n",
                preset.c_str(), backend.c_str(), offset_s, t["estimate_s"].get<double>(),
                t["std_s"].get<double>(), t["excited"].get<bool>() ? 1 : 0, ate, ate_sync);
    EXPECT_TRUE(t["excited"].get<bool>()) << offset_s;
    EXPECT_NEAR(t["estimate_s"].get<double>(), offset_s, 0.002) << preset << " " << backend;
    // The target, 1.2x the synchronized ATE: measured at most 1.06x (IESKF
    // with the replay) and 1.13x (smoother) (docs/time_offset.md).
    EXPECT_LT(ate, 1.2 * ate_sync) << preset << " " << backend << " " << offset_s;
  }
  std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(
    PresetsAndBackends, TimeOffsetMatrix,
    ::testing::Values(std::pair<std::string, std::string>{"tunnel", "ieskf"},
                      std::pair<std::string, std::string>{"tunnel", "smoother"},
                      std::pair<std::string, std::string>{"hall", "ieskf"},
                      std::pair<std::string, std::string>{"hall", "smoother"}),
    [](const auto& info) { return info.param.first + "_" + info.param.second; });

}  // namespace
}  // namespace rvlio

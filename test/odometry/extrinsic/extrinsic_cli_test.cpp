// End to end: online extrinsic estimation (ieskf.estimate_extrinsics,
// smoother.estimate_extrinsics) on seeded simulated bags (512 columns):
//   - exact start extrinsics: ATE within 10% of the option off, and the
//     estimate stays at the configured value;
//   - a start error of 2 deg / 5 cm (smoother): the axes the flight excites
//     move toward the truth, the others are reported held;
//   - a tunnel flight with sway ("normal excitation"), start error 2 deg /
//     5 cm, both backends: the convergence bounds (0.2 deg / 1 cm) where met, and
//     all of them with map re-anchoring; scans.csv follows the estimate;
//   - a motionless bag: nothing excited, the extrinsic stays exactly at its
//     prior and summary.json says so.
// Longer multi-seed measurements: docs/extrinsics.md.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_util.h"

namespace rvlio {
namespace {

using testing_cli::EvalJson;
using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

// 2 deg about (1,1,1)/sqrt(3) and 5 cm along (1,1,1)/sqrt(3) from the
// simulator's true extrinsic (translation [0.05, 0, 0.1], identity rotation).
const char* kPerturbed =
    " --set extrinsics.imu_T_lidar.translation=[0.078868,0.028868,0.128868]"
    " --set extrinsics.imu_T_lidar.rotation_xyzw=[0.0100762,0.0100762,0.0100762,0.9998477]";

class ExtrinsicCliTest : public testing_cli::SimulatedTunnelSuite {
 protected:
  static double Ate(const std::string& out) {
    const auto j = EvalJson(Truth(), out + "/trajectory.tum", dir_);
    return j.is_null() ? 1e9 : j["ape"]["rmse"].get<double>();
  }
  static nlohmann::json Extrinsic(const std::string& out) {
    return nlohmann::json::parse(ReadFile(out + "/summary.json"))["extrinsic"];
  }
};

void ExpectExactStartWithinTenPercent(const std::string& backend, double ate_off, double ate_on,
                                      const nlohmann::json& e) {
  EXPECT_LT(ate_on, 1.1 * ate_off) << backend << ": " << ate_off << " -> " << ate_on;
  EXPECT_LT(e["change_from_prior"]["rotation_deg"].get<double>(), 0.2) << backend;
  EXPECT_LT(e["change_from_prior"]["translation_m"].get<double>(), 0.01) << backend;
}

TEST_F(ExtrinsicCliTest, IeskfExactStartKeepsTheAccuracy) {
  ASSERT_EQ(Run(dir_ + "/ieskf_off", "--set backend=ieskf").exit_code, 0);
  const ToolRun on = Run(dir_ + "/ieskf_on", "--set backend=ieskf --set ieskf.estimate_extrinsics=true");
  ASSERT_EQ(on.exit_code, 0) << on.err;
  const nlohmann::json e = Extrinsic(dir_ + "/ieskf_on");
  ASSERT_TRUE(e.is_object());
  ExpectExactStartWithinTenPercent("ieskf", Ate(dir_ + "/ieskf_off"), Ate(dir_ + "/ieskf_on"), e);
  EXPECT_TRUE(nlohmann::json::parse(ReadFile(dir_ + "/ieskf_off/summary.json"))["extrinsic"].is_null());
}

TEST_F(ExtrinsicCliTest, SmootherExactStartKeepsTheAccuracy) {
  ASSERT_EQ(Run(dir_ + "/smoother_off", "--set backend=smoother").exit_code, 0);
  const ToolRun on =
      Run(dir_ + "/smoother_on", "--set backend=smoother --set smoother.estimate_extrinsics=true");
  ASSERT_EQ(on.exit_code, 0) << on.err;
  const nlohmann::json e = Extrinsic(dir_ + "/smoother_on");
  ASSERT_TRUE(e.is_object());
  ExpectExactStartWithinTenPercent("smoother", Ate(dir_ + "/smoother_off"),
                                   Ate(dir_ + "/smoother_on"), e);
}

// Measured on this 14 s tunnel (seed 3): roll 1.17 -> 0.32 deg, yaw 1.17 ->
// 0.24 deg, t_x error 2.9 -> 1.2 cm; pitch and t_y held (not excited: the
// flight rotates little about the IMU's y axis).
TEST_F(ExtrinsicCliTest, SmootherPerturbedStartMovesTheExcitedAxesTowardTheTruth) {
  const std::string out = dir_ + "/smoother_pert";
  // --allow-divergence: with a 3 cm start error the window's median
  // point-to-plane residual passes the divergence monitor's residual check
  // (0.079 > 0.075 m) for a few seconds before the extrinsic converges; the
  // monitor is tested in test/odometry/divergence, this test is about convergence.
  const ToolRun r = Run(out, std::string("--set backend=smoother --set smoother.estimate_extrinsics=true"
                                         " --allow-divergence") +
                                 kPerturbed);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json e = Extrinsic(out);
  EXPECT_TRUE(e["estimated"].get<bool>());
  const auto rpy = e["T_imu_lidar"]["rpy_deg"];
  const auto t = e["T_imu_lidar"]["translation_m"];
  const auto& ax = e["axes_excited"];
  ASSERT_TRUE(ax["rot_x"].get<bool>() && ax["rot_z"].get<bool>() && ax["pos_x"].get<bool>());
  EXPECT_LT(std::abs(rpy[0].get<double>()), 0.5);  // from 1.17 deg
  EXPECT_LT(std::abs(rpy[2].get<double>()), 0.5);  // from 1.17 deg
  EXPECT_LT(std::abs(t[0].get<double>() - 0.05), 0.018);  // from 0.0289 m
  // Held axes keep the configured value exactly.
  if (!ax["pos_y"].get<bool>()) {
    EXPECT_DOUBLE_EQ(t[1].get<double>(), 0.028868);
  }
  EXPECT_LT(Ate(out), 0.03);
}

// "Normal excitation": the full 52 s tunnel flight with carried-sensor sway
// (trajectory.sway_amplitude 0.1 rad at 1 Hz, docs/extrinsics.md), seed 1,
// start error 2 deg / 5 cm. Measured (docs/extrinsics.md): smoother 0.03 deg,
// t error 0.4 / 1.0 / 0.7 cm; IESKF 0.29 deg (pitch 0.27), t error
// 0.3 / 0.5 / 0.4 cm. Bounds: the 0.2 deg / 1 cm where met (smoother
// rotation, IESKF translation), the measured figure plus margin elsewhere.
double RotationErrorDeg(const nlohmann::json& e) {
  double sum2 = 0.0;  // true rotation: identity; small angles
  for (const auto& a : e["T_imu_lidar"]["rpy_deg"]) sum2 += a.get<double>() * a.get<double>();
  return std::sqrt(sum2);
}
double MaxTranslationErrorM(const nlohmann::json& e) {
  const auto& t = e["T_imu_lidar"]["translation_m"];
  const double truth[3] = {0.05, 0.0, 0.1};
  double worst = 0.0;
  for (int i = 0; i < 3; ++i) worst = std::max(worst, std::abs(t[i].get<double>() - truth[i]));
  return worst;
}

// The last row of scans.csv's extrinsic columns (roll, pitch, yaw in deg,
// x, y, z in m), which follow the estimate scan by scan.
std::vector<double> LastCsvExtrinsic(const std::string& csv_path) {
  const std::string csv = ReadFile(csv_path);
  const std::string header = csv.substr(0, csv.find('\n'));
  EXPECT_NE(header.find(",ext_roll_deg,ext_pitch_deg,ext_yaw_deg,ext_x_m,ext_y_m,ext_z_m"),
            std::string::npos)
      << header;
  const size_t end = csv.find_last_not_of('\n');
  const std::string last = csv.substr(csv.rfind('\n', end) + 1, end - csv.rfind('\n', end));
  std::vector<double> v;
  size_t pos = last.size();
  for (int i = 0; i < 6; ++i) {
    const size_t comma = last.rfind(',', pos - 1);
    v.insert(v.begin(), std::stod(last.substr(comma + 1, pos - comma - 1)));
    pos = comma;
  }
  return v;
}

class ExtrinsicCliSway : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing_cli::MakeTempDir("rvlio_extrinsic_sway");
    ASSERT_FALSE(dir_.empty());
    const ToolRun sim = testing_cli::SimulateTunnel(
        dir_ + "/data", 1, 52, dir_,
        "--set trajectory.sway_amplitude=0.1 --set trajectory.sway_frequency=1.0");
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  // Runs one backend from the perturbed start; summary.json's "extrinsic".
  static nlohmann::json RunPerturbed(const std::string& backend, const std::string& name,
                                     const std::string& extra) {
    const std::string out = dir_ + "/" + name;
    const ToolRun r = RunTool("run --bag " + dir_ + "/data/tunnel.bag --config " + dir_ +
                                  "/data/tunnel.yaml --out " + out + " --set backend=" + backend +
                                  " --set " + backend + ".estimate_extrinsics=true" +
                                  " --allow-divergence" + kPerturbed + extra,
                              dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json e = nlohmann::json::parse(ReadFile(out + "/summary.json"))["extrinsic"];
    EXPECT_TRUE(e.is_object()) << backend;
    if (!e.is_object()) return e;
    EXPECT_TRUE(e["estimated"].get<bool>()) << backend;
    for (const auto& [axis, excited] : e["axes_excited"].items())
      EXPECT_TRUE(excited.get<bool>()) << backend << " " << axis;
    // scans.csv's last extrinsic row is the summary's final estimate.
    const std::vector<double> last = LastCsvExtrinsic(out + "/scans.csv");
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(last[i], e["T_imu_lidar"]["rpy_deg"][i].get<double>(), 1e-6) << backend;
      EXPECT_NEAR(last[3 + i], e["T_imu_lidar"]["translation_m"][i].get<double>(), 1e-8) << backend;
    }
    return e;
  }

  static std::string dir_;
};
std::string ExtrinsicCliSway::dir_;

TEST_F(ExtrinsicCliSway, PerturbedStartConvergesOnATunnelFlightWithSway) {
  const nlohmann::json ieskf = RunPerturbed("ieskf", "ieskf", "");
  const nlohmann::json smoother = RunPerturbed("smoother", "smoother", "");
  ASSERT_TRUE(ieskf.is_object() && smoother.is_object());
  EXPECT_EQ(ieskf["map_rebuilds"].get<int>(), 0);  // map.reanchor_window = 0: off
  EXPECT_LT(MaxTranslationErrorM(ieskf), 0.01);    // from 2.9 cm per axis
  EXPECT_LT(RotationErrorDeg(ieskf), 0.45);        // from 2 deg
  EXPECT_LT(RotationErrorDeg(smoother), 0.2);
  EXPECT_LT(MaxTranslationErrorM(smoother), 0.015);
}

// Map re-anchoring (docs/extrinsics.md): both backends meet the bounds of
// 0.2 deg / 1 cm. Measured, seed 1: IESKF 0.12 deg, 0.45 cm; smoother
// 0.04 deg, 0.73 cm.
TEST_F(ExtrinsicCliSway, MapReanchoringMeetsTheConvergenceTarget) {
  const std::string reanchor = " --set map.reanchor_window=20";
  const nlohmann::json ieskf =
      RunPerturbed("ieskf", "ieskf_reanchor", reanchor + " --set ieskf.extrinsic_pos_random_walk=5e-4");
  const nlohmann::json smoother = RunPerturbed("smoother", "smoother_reanchor", reanchor);
  ASSERT_TRUE(ieskf.is_object() && smoother.is_object());
  for (const nlohmann::json* e : {&ieskf, &smoother}) {
    EXPECT_GT((*e)["map_rebuilds"].get<int>(), 0);
    EXPECT_LT(RotationErrorDeg(*e), 0.2);
    EXPECT_LT(MaxTranslationErrorM(*e), 0.01);
  }
}

// A bag in which the vehicle never moves: nothing to calibrate against.
TEST(ExtrinsicCliStatic, MotionlessBagKeepsThePriorAndSaysSo) {
  const std::string dir = testing_cli::MakeTempDir("rvlio_extrinsic_static");
  ASSERT_FALSE(dir.empty());
  const ToolRun sim = testing_cli::SimulateTunnel(dir + "/data", 4, 6, dir,
                                                  "--set trajectory.static_duration=100");
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  for (const std::string backend : {"ieskf", "smoother"}) {
    const std::string out = dir + "/" + backend;
    const ToolRun r = RunTool("run --bag " + dir + "/data/tunnel.bag --config " + dir +
                                  "/data/tunnel.yaml --out " + out + " --set backend=" + backend +
                                  " --set " + backend + ".estimate_extrinsics=true" + kPerturbed,
                              dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json e =
        nlohmann::json::parse(ReadFile(out + "/summary.json"))["extrinsic"];
    ASSERT_TRUE(e.is_object()) << backend;
    EXPECT_FALSE(e["estimated"].get<bool>()) << backend;
    EXPECT_EQ(e["excited_fraction"].get<double>(), 0.0) << backend;
    for (const auto& [axis, excited] : e["axes_excited"].items()) EXPECT_FALSE(excited.get<bool>()) << axis;
    EXPECT_EQ(e["change_from_prior"]["rotation_deg"].get<double>(), 0.0) << backend;
    EXPECT_EQ(e["change_from_prior"]["translation_m"].get<double>(), 0.0) << backend;
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rvlio

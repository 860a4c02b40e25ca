// End to end: localization in a reference map (`rvlio run --map`,
// `rvlio refine --map`; docs/survey.md). The reference is a map of the same
// simulated tunnel in the ground truth's frame.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "cli_util.h"
#include "rvlio/outputs/run_outputs.h"
#include "rvlio/formats/trajectory_io.h"

namespace rvlio {
namespace {

using testing_cli::AteNoAlign;
using testing_cli::IeskfTunnelSuite;
using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

// "x,y,z,roll,pitch,yaw" of `pose` moved by dp_m (world) and rotated by
// drot_deg about yaw, pitch and roll each (so the text's angles are off).
std::string PoseText(const StampedPose& pose, const Eigen::Vector3d& dp_m, double drot_deg) {
  const Eigen::Matrix3d R = pose.q_world_imu.toRotationMatrix();
  const Eigen::Vector3d ypr = R.eulerAngles(2, 1, 0) * 180.0 / M_PI;  // yaw, pitch, roll
  const Eigen::Vector3d p = pose.p_world_imu + dp_m;
  char text[256];
  std::snprintf(text, sizeof(text), "%.6f,%.6f,%.6f,%.6f,%.6f,%.6f", p.x(), p.y(), p.z(),
                ypr[2] + drot_deg, ypr[1] - drot_deg, ypr[0] + drot_deg);
  return text;
}

// The reference: the suite's IESKF map (in the ground truth's frame: the
// run starts at the simulated start pose). The first estimated pose is
// where the localized runs start from, with errors added.
class SurveyCli : public IeskfTunnelSuite {
 protected:
  static std::string Reference() { return dir_ + "/ieskf/map.pcd"; }
  static StampedPose FirstPose() {
    StatusOr<Trajectory> t = ReadTum(dir_ + "/ieskf/trajectory.tum");
    return t.ok() && !t->empty() ? t->front() : StampedPose();
  }
  static ToolRun RunWithMap(const std::string& out, const std::string& extra) {
    return Run(out, "--map " + Reference() + " " + extra);
  }
  static std::string Out(const std::string& name) { return dir_ + "/" + name; }
};

// A wrong start (metres and degrees) converges for both backends; the run is
// in the reference's frame (no alignment needed) and reports its overlap.
class SurveyStart : public SurveyCli,
                    public ::testing::WithParamInterface<std::tuple<std::string, double, double>> {};

TEST_P(SurveyStart, ConvergesAndStaysInTheReferenceFrame) {
  const auto& [backend, dp_m, drot_deg] = GetParam();
  const std::string out = Out("start_" + backend + "_" + std::to_string(dp_m));
  const Eigen::Vector3d dp = Eigen::Vector3d(0.3, -0.8, 0.52).normalized() * dp_m;
  const ToolRun r = RunWithMap(out, "--set backend=" + backend + " --initial-pose " +
                                        PoseText(FirstPose(), dp, drot_deg / std::sqrt(3.0)));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double ate = AteNoAlign(Truth(), out + "/trajectory.tum", dir_);
  EXPECT_LT(ate, 0.05) << backend;
  std::printf("[ survey ] %s from %.1f m / %.0f deg: ATE (no alignment) %.4f m\n",
              backend.c_str(), dp_m, drot_deg, ate);
  const std::string csv = ReadFile(out + "/scans.csv");
  EXPECT_NE(csv.substr(0, csv.find('\n')).find(",map_overlap,localized"), std::string::npos);
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(out + "/summary.json"));
  EXPECT_EQ(summary["localization"]["localized_scans"].get<int>(), summary["scan_count"].get<int>());
  EXPECT_TRUE(summary["localization"]["out_of_map_spans"].empty());
}

INSTANTIATE_TEST_SUITE_P(
    Backends, SurveyStart,
    ::testing::Values(std::make_tuple("ieskf", 0.5, 3.0), std::make_tuple("ieskf", 1.0, 5.0),
                      std::make_tuple("smoother", 0.5, 3.0), std::make_tuple("smoother", 1.0, 5.0)));

TEST_F(SurveyCli, InitialPoseFromATumFileAndRefineHeldToTheMap) {
  const std::string run = Out("tum_start");
  ToolRun r = RunWithMap(run, "--initial-pose-tum " + Truth());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double run_ate = AteNoAlign(Truth(), run + "/trajectory.tum", dir_);
  EXPECT_LT(run_ate, 0.05);
  const std::string refined = Out("refined");
  r = RunTool("refine --bag " + Bag() + " --config " + Sensors() + " --init " + run +
                  "/trajectory.tum --map " + Reference() + " --out " + refined,
              dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double refine_ate = AteNoAlign(Truth(), refined + "/trajectory.tum", dir_);
  EXPECT_LT(refine_ate, 0.05);
  // The refined map's deviation from the reference (the same flight's map).
  const nlohmann::json dev =
      nlohmann::json::parse(ReadFile(refined + "/summary.json"))["localization"]["deviation"];
  EXPECT_GT(dev["with_surface"].get<double>(), 0.5 * dev["map_points"].get<double>());
  EXPECT_LT(dev["median_abs_m"].get<double>(), 0.02);
  EXPECT_TRUE(std::filesystem::exists(refined + "/deviation.csv"));
  EXPECT_NE(ReadFile(refined + "/map.pcd")
                .substr(0, 400)
                .find("FIELDS x y z intensity time ring scan_index deviation_m"),
            std::string::npos);
  std::printf("[ survey ] run --map %.4f m, refine --map %.4f m (ATE, no alignment)\n", run_ate,
              refine_ate);
}

// Bad inputs: exit 2, one line naming the file or option, nothing written.
class SurveyBadInput : public SurveyCli {
 protected:
  void ExpectRefused(const std::string& args, const std::string& named) {
    const std::string out = Out("refused");
    std::filesystem::remove_all(out);
    const ToolRun r = Run(out, args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(named), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << args;
  }
  std::string Pose() { return " --initial-pose " + PoseText(FirstPose(), Eigen::Vector3d::Zero(), 0.0); }
};

TEST_F(SurveyBadInput, MissingEmptyTruncatedOrNonFiniteMap) {
  ExpectRefused("--map " + Out("nothing.pcd") + Pose(), "nothing.pcd");
  const std::string empty = Out("empty.pcd");
  ASSERT_TRUE(WriteMapPcd(empty, {}).ok());
  ExpectRefused("--map " + empty + Pose(), "empty.pcd");
  const std::string text = ReadFile(Reference());
  const std::string truncated = Out("truncated.pcd");
  std::ofstream(truncated, std::ios::binary) << text.substr(0, text.size() / 2);
  ExpectRefused("--map " + truncated + Pose(), "truncated.pcd");
  StatusOr<std::vector<Eigen::Vector3d>> points = ReadMapPcd(Reference());
  ASSERT_TRUE(points.ok());
  std::vector<Eigen::Vector3d> with_nan = *points;
  with_nan[with_nan.size() / 2].y() = NAN;
  ASSERT_TRUE(WriteMapPcd(Out("nan.pcd"), with_nan).ok());
  ExpectRefused("--map " + Out("nan.pcd") + Pose(), "nan.pcd");
  const std::string garbage = Out("garbage.ply");
  std::ofstream(garbage) << "not a point cloud\n";
  ExpectRefused("--map " + garbage + Pose(), "garbage.ply");
}

TEST_F(SurveyBadInput, MapInMillimetresOrFarFromTheStart) {
  StatusOr<std::vector<Eigen::Vector3d>> points = ReadMapPcd(Reference());
  ASSERT_TRUE(points.ok());
  std::vector<Eigen::Vector3d> mm = *points;
  for (Eigen::Vector3d& p : mm) p *= 1000.0;
  ASSERT_TRUE(WriteMapPcd(Out("mm.pcd"), mm).ok());
  ExpectRefused("--map " + Out("mm.pcd") + Pose(), "mm.pcd");
  ExpectRefused("--map " + Reference() + " --initial-pose 500,0,0,0,0,0", "map.pcd");
}

TEST_F(SurveyBadInput, MalformedOrMissingInitialPose) {
  ExpectRefused("--map " + Reference() + " --initial-pose 1,2,3", "--initial-pose");
  ExpectRefused("--map " + Reference() + " --initial-pose 1,2,3,4,5,x", "--initial-pose");
  ExpectRefused("--map " + Reference() + " --initial-pose 1,2,3,4,5,nan", "--initial-pose");
  ExpectRefused("--map " + Reference() + " --initial-pose-tum " + Out("none.tum"),
                "--initial-pose-tum");
  ExpectRefused(Pose(), "--map");
}

// The start judged from the static scans (docs/survey.md "Ambiguous starts
// are refused"): a 6 s tunnel flight (3 s at rest) and its survey, and the
// survey of another world (the hall). Runs of --duration 2.9 hold the static
// scans only.
class SurveyStartCheck : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing_cli::MakeTempDir("rvlio_startcheck");
    ASSERT_FALSE(dir_.empty());
    ToolRun sim = testing_cli::CachedSimulate(
        "--preset tunnel --seed 1 --duration 6 --set lidar.columns=512 --reference-map"
        " --set survey.x_min=-10 --set survey.x_max=30",
        dir_ + "/sim", dir_);
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
    sim = testing_cli::CachedSimulate("--preset hall --seed 1 --duration 1 --reference-map-only"
                                      " --set survey.x_min=-10 --set survey.x_max=30",
                                      dir_ + "/hall", dir_);
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }
  static std::string Survey() { return dir_ + "/sim/reference_map.pcd"; }
  static std::string Hall() { return dir_ + "/hall/reference_map.pcd"; }
  static std::string Truth() { return dir_ + "/sim/tunnel_gt.tum"; }
  static ToolRun Run(const std::string& out, const std::string& args) {
    return RunTool("run --quiet --bag " + dir_ + "/sim/tunnel.bag --config " + dir_ +
                       "/sim/tunnel.yaml --out " + out + " " + args,
                   dir_);
  }
  static void ExpectRefused(const std::string& args, const std::string& named,
                            const std::string& reason) {
    const std::string out = dir_ + "/refused";
    const ToolRun r = Run(out, "--duration 2.9 " + args);
    testing_cli::ExpectOneErrorLine(r, "run", named);
    EXPECT_NE(r.err.find(reason), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << args;
  }
  static inline std::string dir_;
};

TEST_F(SurveyStartCheck, WrongStartOrMapIsRefusedFromTheStaticScans) {
  ASSERT_EQ(Run(dir_ + "/true", "--duration 2.9 --map " + Survey() + " --initial-pose-tum " +
                                    Truth()).exit_code, 0);
  // 2 m along the tunnel, or turned round: the scan fits better at the truth.
  ExpectRefused("--map " + Survey() + " --initial-pose 2,0,0,0,0,0", "--initial-pose",
                "fits the reference map better at (0.00, ");
  ExpectRefused("--map " + Survey() + " --initial-pose 0,0,0,0,0,180", "--initial-pose",
                "fits the reference map better at (0.00, ");
  // Another world's survey: nowhere as a scan of the mapped place fits it.
  ExpectRefused("--map " + Hall() + " --initial-pose-tum " + Truth(), Hall(),
                "check that the map is of this place");
}

// A start that is let through (trusted, and a looser fit) diverges while
// the platform is still at rest: the message names the start and the map,
// not the extrinsic or the clocks.
TEST_F(SurveyStartCheck, DivergenceAtRestNamesTheStartAndTheMap) {
  const ToolRun r = Run(dir_ + "/trusted", "--map " + Survey() +
                                                " --initial-pose 2,0,0,0,0,0"
                                                " --set localization.trust_initial_pose=true"
                                                " --set localization.min_start_fit=0.8");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  const std::string last = r.err.substr(r.err.rfind("rvlio run: error:"));
  EXPECT_NE(last.find("the start pose (--initial-pose) or the map (--map) is wrong"),
            std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("check the extrinsic rotation"), std::string::npos) << r.err;
}

// refine --map checks the map as run --map does: another world's map and a
// map 1000 m away are refused (exit 2, one line naming --map, nothing written).
TEST_F(SurveyStartCheck, RefineRefusesAMapThatDoesNotFit) {
  const std::string run = dir_ + "/run";
  ASSERT_EQ(Run(run, "--map " + Survey() + " --initial-pose-tum " + Truth()).exit_code, 0);
  StatusOr<std::vector<Eigen::Vector3d>> points = ReadMapPcd(Survey());
  ASSERT_TRUE(points.ok());
  for (Eigen::Vector3d& p : *points) p.x() += 1000.0;
  const std::string far = dir_ + "/far.pcd";
  ASSERT_TRUE(WriteMapPcd(far, *points).ok());
  for (const std::string& map : {Hall(), far}) {
    const std::string out = dir_ + "/refined";
    const ToolRun r = RunTool("refine --bag " + dir_ + "/sim/tunnel.bag --config " + dir_ +
                                  "/sim/tunnel.yaml --init " + run + "/trajectory.tum --map " +
                                  map + " --out " + out,
                              dir_);
    testing_cli::ExpectOneErrorLine(r, "refine", "--map " + map);
    EXPECT_FALSE(std::filesystem::exists(out)) << map;
  }
}

}  // namespace
}  // namespace rvlio

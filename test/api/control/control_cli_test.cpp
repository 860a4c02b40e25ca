// `rvlio refine --control` end to end on one short simulated stop-and-go
// flight (4 marks 10 m apart in a UTM-sized survey frame, 512 columns,
// simulated once: CachedSimulate), and every bad input of the control file
// with its one line and nothing written (docs/control.md).
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli/cli_util.h"
#include "rvlio/math/pose_interpolation.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/refine/states.h"

namespace rvlio {
namespace {

using testing_cli::ExpectOneErrorLine;
using testing_cli::ReadFile;
using testing_cli::RunTool;
namespace fs = std::filesystem;

constexpr double kStartHeight = 0.3;  // world.start_height: the lever arm's z

// marks at 0, 10, 20, 30 m; M3 is a check point (marks.check_every 3).
const char* const kSimArgs =
    "--preset stopgo --seed 4 --duration 50 --name sg --set lidar.columns=512"
    " --set \"trajectory.waypoints=0,0,0; 0,0,1; 10,0,1; 10,0,0; 10,0,1; 20,0,1; 20,0,0;"
    " 20,0,1; 30,0,1; 30,0,0\" --set trajectory.landing_time=3 --set marks.check_every=3"
    " --set world.length=45";

class ControlCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing_cli::MakeTempDir("rvlio_control");
    data_ = dir_ + "/data";
    const testing_cli::ToolRun sim = testing_cli::CachedSimulate(kSimArgs, data_, dir_);
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
  }
  void TearDown() override { fs::remove_all(dir_); }

  // refine with the ground truth (world frame) as --init: bad inputs are
  // refused before the solve.
  testing_cli::ToolRun Refine(const std::string& control, const std::string& out,
                              const std::string& extra = "") {
    return RunTool("refine --bag " + data_ + "/sg.bag --config " + data_ + "/sg.yaml --init " +
                       data_ + "/sg_gt.tum --control " + control + " --out " + out + " " + extra,
                   dir_);
  }
  std::string Write(const std::string& name, const std::string& text) {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path) << text;
    return path;
  }
  // The control file's rows after the header.
  std::vector<std::string> MarkRows() {
    std::vector<std::string> rows;
    std::istringstream in(ReadFile(data_ + "/sg_control.csv"));
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) rows.push_back(line);
    return rows;
  }

  std::string dir_, data_;
};

// The flight tied to three control marks: outputs in the survey frame, the
// check point's residual is its true error, summary and control.csv agree;
// then tied by three wall targets instead.
TEST_F(ControlCli, RunThenRefineWithMarksOrWallTargetsDeliversInTheSurveyFrame) {
  const std::string run = dir_ + "/run", out = dir_ + "/refined";
  const testing_cli::ToolRun r = RunTool("run --bag " + data_ + "/sg.bag --config " + data_ +
                                             "/sg.yaml --out " + run + " --quiet --control " +
                                             data_ + "/sg_control.csv",
                                         dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("--control is used by refine"), std::string::npos) << r.err;
  const testing_cli::ToolRun f =
      RunTool("refine --bag " + data_ + "/sg.bag --config " + data_ + "/sg.yaml --init " + run +
                  "/trajectory.tum --control " + data_ + "/sg_control.csv --out " + out +
                  " --set refine.rounds=2",
              dir_);
  ASSERT_EQ(f.exit_code, 0) << f.err;
  EXPECT_NE(f.out.find("control points: 3"), std::string::npos) << f.out;
  // ATE without alignment against the survey-frame ground truth.
  const double ate = testing_cli::AteNoAlign(data_ + "/sg_gt_survey.tum", out + "/trajectory.tum", dir_);
  EXPECT_LT(ate, 0.05) << "ATE in the survey frame, no alignment";
  // control.csv: the check point's residual equals its true error (the
  // estimate against the true mark under the true IMU) within a few mm.
  std::istringstream csv(ReadFile(out + "/control.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "name,role,kind,x,y,z,x_est,y_est,z_est,dx,dy,dz,d3d,sigma_m,t_s,scans");
  StatusOr<Trajectory> gt = ReadTum(data_ + "/sg_gt_survey.tum");
  ASSERT_TRUE(gt.ok());
  int rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    std::vector<std::string> c;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) c.push_back(cell);
    ASSERT_EQ(c.size(), 16u) << line;
    const Eigen::Vector3d est(std::stod(c[6]), std::stod(c[7]), std::stod(c[8]));
    const Eigen::Vector3d reported(std::stod(c[9]), std::stod(c[10]), std::stod(c[11]));
    Pose3 T;
    ASSERT_TRUE(InterpolatePose(*gt, SecondsToNs(std::stod(c[14])), &T));
    const Eigen::Vector3d true_mark = T.t - Eigen::Vector3d(0, 0, kStartHeight);
    const Eigen::Vector3d true_error = est - true_mark;
    EXPECT_LT((reported - true_error).norm(), 0.008) << line;  // the marks' noise: 2 mm per axis
    if (c[1] == "check") {
      EXPECT_LT(reported.norm(), 0.05) << line;
    }
  }
  EXPECT_EQ(rows, 4);
  const nlohmann::json s = nlohmann::json::parse(ReadFile(out + "/summary.json"));
  EXPECT_EQ(s["survey"]["control_points"], 3);
  EXPECT_EQ(s["survey"]["check_points"], 1);
  EXPECT_NEAR(s["survey"]["alignment"]["yaw_deg"].get<double>(), 30.0, 1.0);
  EXPECT_EQ(s["control"]["check"]["count"], 1);
  EXPECT_EQ(s["control"]["check"]["max_name"], "M3");

  // The same flight tied by wall targets instead of marks: three spots on
  // the walls of the run's map.pcd, their survey coordinates carried over
  // from the run's frame by the true pose at the nearest moment.
  StatusOr<PointCloudFile> map = ReadPointCloud(run + "/map.pcd");
  ASSERT_TRUE(map.ok()) << map.status().message();
  StatusOr<Trajectory> est = ReadTum(run + "/trajectory.tum");
  ASSERT_TRUE(est.ok());
  std::string targets = "name,x,y,z,map_x,map_y,map_z\n";
  for (double x : {4.0, 15.0, 26.0}) {
    const Eigen::Vector3d* spot = nullptr;
    for (const Eigen::Vector3d& p : map->points)
      if (std::abs(p.x() - x) < 0.3 && p.y() > 4.0 && p.z() > 0.5 && p.z() < 2.5) spot = &p;
    ASSERT_NE(spot, nullptr) << x;
    const StampedPose* near = &est->front();
    for (const StampedPose& q : *est)
      if ((q.p_world_imu - *spot).norm() < (near->p_world_imu - *spot).norm()) near = &q;
    Pose3 T_survey_imu;
    ASSERT_TRUE(InterpolatePose(*gt, near->t_ns, &T_survey_imu));
    const Eigen::Vector3d p_survey =
        T_survey_imu * (Pose3(near->q_world_imu, near->p_world_imu).Inverse() * *spot);
    char text[256];
    std::snprintf(text, sizeof(text), "T%d,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n", static_cast<int>(x),
                  p_survey.x(), p_survey.y(), p_survey.z(), spot->x(), spot->y(), spot->z());
    targets += text;
  }
  std::ofstream(dir_ + "/targets.csv") << targets;
  const std::string tied = dir_ + "/targets";
  const testing_cli::ToolRun t =
      RunTool("refine --bag " + data_ + "/sg.bag --config " + data_ + "/sg.yaml --init " + run +
                  "/trajectory.tum --control " + dir_ + "/targets.csv --out " + tied +
                  " --set refine.rounds=1",
              dir_);
  ASSERT_EQ(t.exit_code, 0) << t.err;
  EXPECT_LT(testing_cli::AteNoAlign(data_ + "/sg_gt_survey.tum", tied + "/trajectory.tum", dir_),
            0.06);
  const std::string tied_csv = ReadFile(tied + "/control.csv");
  EXPECT_NE(tied_csv.find("T15,control,target,"), std::string::npos) << tied_csv;
  const nlohmann::json ts = nlohmann::json::parse(ReadFile(tied + "/summary.json"));
  EXPECT_EQ(ts["survey"]["targets"], 3);
  EXPECT_LT(ts["control"]["control"]["max_m"].get<double>(), 0.05);

  // Large coordinates: the same marks moved to a local frame near zero give
  // the same residuals and the same trajectory (moved back) to 1 mm.
  const Eigen::Vector3d offset(500000.0, 5400000.0, 250.0);
  std::string local = "name,x,y,z,role\n";
  for (const std::string& row : MarkRows()) {
    std::vector<std::string> c;
    std::istringstream cells(row);
    for (std::string cell; std::getline(cells, cell, ',');) c.push_back(cell);
    char text[160];
    std::snprintf(text, sizeof(text), "%s,%.4f,%.4f,%.4f,%s\n", c[0].c_str(),
                  std::stod(c[1]) - offset.x(), std::stod(c[2]) - offset.y(),
                  std::stod(c[3]) - offset.z(), c[4].c_str());
    local += text;
  }
  std::ofstream(dir_ + "/local.csv") << local;
  for (const std::string& frame : {std::string("utm"), std::string("local")}) {
    const testing_cli::ToolRun l =
        RunTool("refine --bag " + data_ + "/sg.bag --config " + data_ + "/sg.yaml --init " + run +
                    "/trajectory.tum --control " +
                    (frame == "utm" ? data_ + "/sg_control.csv" : dir_ + "/local.csv") + " --out " +
                    dir_ + "/" + frame + " --set refine.rounds=1",
                dir_);
    ASSERT_EQ(l.exit_code, 0) << l.err;
  }
  const std::string utm_csv = ReadFile(dir_ + "/utm/control.csv");
  const std::string local_csv = ReadFile(dir_ + "/local/control.csv");
  std::istringstream u(utm_csv), v(local_csv);
  std::string lu, lv;
  std::getline(u, lu);
  std::getline(v, lv);
  while (std::getline(u, lu) && std::getline(v, lv)) {
    std::vector<std::string> cu, cv;
    std::istringstream su(lu), sv(lv);
    for (std::string cell; std::getline(su, cell, ',');) cu.push_back(cell);
    for (std::string cell; std::getline(sv, cell, ',');) cv.push_back(cell);
    ASSERT_EQ(cu.size(), 16u);
    for (int k = 9; k <= 12; ++k) EXPECT_NEAR(std::stod(cu[k]), std::stod(cv[k]), 0.001) << lu;
  }
  StatusOr<Trajectory> tu = ReadTum(dir_ + "/utm/trajectory.tum");
  StatusOr<Trajectory> tv = ReadTum(dir_ + "/local/trajectory.tum");
  ASSERT_TRUE(tu.ok() && tv.ok());
  ASSERT_EQ(tu->size(), tv->size());
  double worst = 0.0;
  for (size_t k = 0; k < tu->size(); ++k)
    worst = std::max(worst, ((*tu)[k].p_world_imu - offset - (*tv)[k].p_world_imu).norm());
  EXPECT_LT(worst, 0.001);
}

// The simulator's marks (one test process: each copies the simulation),
// then every bad control file.
TEST_F(ControlCli, SimulatedMarksAndBadControlFilesRefusedWithOneLineNothingWritten) {
  const std::vector<std::string> rows = MarkRows();
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[2].substr(0, 3), "M3,");
  EXPECT_NE(rows[2].find(",check"), std::string::npos);
  EXPECT_NE(rows[0].find(",control"), std::string::npos);
  // M1 (the start) lies at the survey frame's origin (E, N) and 0.3 m below h + IMU height.
  EXPECT_NE(rows[0].find("M1,500000.0"), std::string::npos) << rows[0];
  EXPECT_TRUE(fs::exists(data_ + "/sg_gt_survey.tum"));
  EXPECT_NE(ReadFile(data_ + "/sg.yaml").find("lever_arm: [0, 0, 0.3]"), std::string::npos);
  const std::vector<std::string> m = rows;
  const std::string out = dir_ + "/never";
  struct Case {
    std::string name, text, part;
  };
  // A typo: M4's easting (5000xx.xxxx) 100 m off.
  std::string typo = m[3];
  ASSERT_EQ(typo.substr(3, 4), "5000");
  typo[6] = '1';
  const std::vector<Case> cases = {
      {"nocol.csv", "name,x,y\nM1,1,2\n", "lacks the column 'z'"},
      {"one.csv", "name,x,y,z,role\n" + m[0] + "\n" + m[2] + "\n", "at least 2 are needed"},
      {"oneplace.csv",
       "name,x,y,z,t_start,t_end\nA,500000,5400000,250,1700000000.2,1700000002\n"
       "B,500000.2,5400000,250,1700000000.2,1700000002\n",
       "cannot fix the heading"},
      {"rests.csv", "name,x,y,z,role\n" + m[0] + "\n" + m[1] + "\n" + m[2] + "\n" + m[3] + "\nM5,1,2,3,\n",
       "5 stop-and-go row(s) without t_start,t_end, but the IMU shows 4 rest period(s)"},
      {"target.csv", "name,x,y,z,role,map_x,map_y,map_z\n" + m[0] + ",,,\n" + m[1] + ",,,\n" +
                         m[2] + ",,,\n" + m[3] + ",,,\n" + "T1,500000,5400000,255,,500,500,500\n",
       "line 6 (T1): no scan saw the target"},
      {"typo.csv", "name,x,y,z,role\n" + m[0] + "\n" + m[1] + "\n" + m[2] + "\n" + typo + "\n",
       "line 5 (M4)"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    ExpectOneErrorLine(Refine(Write(c.name, c.text), out), "refine", c.part);
    EXPECT_FALSE(fs::exists(out));
  }
  // An unknown CRS with GNSS; a control file that is not there.
  ExpectOneErrorLine(Refine(data_ + "/sg_control.csv", out,
                            "--set gnss.topic=/gnss/fix --set survey.crs=EPSG:999999"),
                     "refine", "EPSG:999999");
  ExpectOneErrorLine(Refine(dir_ + "/missing.csv", out), "refine", "missing.csv");
  EXPECT_FALSE(fs::exists(out));
}



// A 40 s flight through an 8 m tunnel open at both ends: out of the entrance,
// back in to land on a mark 3 m inside, and out beyond the far portal. GNSS
// fixes (with dropouts and multipath outliers) outside only; the start and
// the landing are the marks inside.
const char* const kPortalArgs =
    "--preset portals --seed 6 --duration 40 --name po --set lidar.columns=512"
    " --set world.length=8 --set \"trajectory.waypoints=0,0,0; 0,0,1; -6,0,1; 3,0,1; 3,0,0;"
    " 3,0,1; 14,0,1\" --set trajectory.landing_time=3 --set trajectory.yaw_amplitude=0"
    " --set imu.vibration_accel=0.3 --set imu.vibration_gyro=0.02 --set marks.enabled=true"
    " --set gnss.outlier_rate=0.05";

TEST(ControlGnssCli, GnssAtBothPortalsWithAndWithoutControlPointsInside) {
  const std::string dir = testing_cli::MakeTempDir("rvlio_gnss"), data = dir + "/data";
  const testing_cli::ToolRun sim = testing_cli::CachedSimulate(kPortalArgs, data, dir);
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const std::string common = "--bag " + data + "/po.bag --config " + data + "/po.yaml";
  ASSERT_EQ(RunTool("run " + common + " --out " + dir + "/run --quiet", dir).exit_code, 0);
  for (const bool marks : {false, true}) {
    SCOPED_TRACE(marks ? "GNSS and the marks inside" : "GNSS alone");
    const std::string out = dir + (marks ? "/both" : "/gnss");
    const testing_cli::ToolRun f =
        RunTool("refine " + common + " --init " + dir + "/run/trajectory.tum --out " + out +
                    " --set refine.rounds=1" +
                    (marks ? " --control " + data + "/po_control.csv" : std::string()),
                dir);
    ASSERT_EQ(f.exit_code, 0) << f.err;
    EXPECT_LT(testing_cli::AteNoAlign(data + "/po_gt_survey.tum", out + "/trajectory.tum", dir),
              0.05);
    const nlohmann::json s = nlohmann::json::parse(ReadFile(out + "/summary.json"));
    EXPECT_EQ(s["survey"]["crs"], "EPSG:25832");
    EXPECT_GT(s["survey"]["gnss_fixes"].get<int>(), 20);
    EXPECT_EQ(s["survey"]["control_points"], marks ? 2 : 0);
    EXPECT_EQ(fs::exists(out + "/control.csv"), marks);
  }
  // An unknown CRS for the fixes: one line, nothing written.
  ExpectOneErrorLine(RunTool("refine " + common + " --init " + dir +
                                 "/run/trajectory.tum --out " + dir + "/never" +
                                 " --set survey.crs=EPSG:999999",
                             dir),
                     "refine", "EPSG:999999");
  EXPECT_FALSE(fs::exists(dir + "/never"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rvlio

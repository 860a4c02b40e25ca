// End to end: survey-sized coordinates (docs/survey.md "Coordinates"). One
// simulated flight localized in its reference map as simulated (near zero)
// and with the map (float64 PCD) and the initial pose moved to a UTM easting
// and northing: the same trajectory, shifted, and the same deviation, to
// 1 mm; refine --map and eval --map of the shifted inputs as well.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_util.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/outputs/run_outputs.h"

namespace rvlio {
namespace {

using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

const Eigen::Vector3d kUtm(500000.0, 5400000.0, 0.0);  // easting, northing, height (m)
constexpr double kMm = 1e-3;

// |a - b| <= tol, or both NaN.
bool Near(double a, double b, double tol) {
  return (std::isnan(a) && std::isnan(b)) || std::abs(a - b) <= tol;
}

// Every column of two CSV files agrees to 1 mm (or both NaN), the
// `shifted` columns after subtracting kUtm's x, y, z from the second file's.
// Timings (ms, rss_mb) vary from run to run and are left out.
void ExpectSameCsv(const std::string& a_path, const std::string& b_path,
                   const std::vector<std::string>& shifted) {
  const auto a = testing_cli::ReadCsv(a_path), b = testing_cli::ReadCsv(b_path);
  ASSERT_FALSE(a.empty()) << a_path;
  ASSERT_EQ(a.size(), b.size()) << b_path;
  for (size_t i = 0; i < a.size(); ++i)
    for (const auto& [name, value] : a[i]) {
      if (name == "ms" || name == "rss_mb") continue;
      const auto axis = std::find(shifted.begin(), shifted.end(), name);
      const double shift = axis == shifted.end() ? 0.0 : kUtm[axis - shifted.begin()];
      EXPECT_TRUE(Near(value, b[i].at(name) - shift, kMm))
          << b_path << " row " << i << " " << name << ": " << value << " vs " << b[i].at(name);
    }
}

class SurveyCoordinates : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing_cli::MakeTempDir("rvlio_utm");
    ASSERT_FALSE(dir_.empty());
    const ToolRun sim = testing_cli::CachedSimulate(
        "--preset tunnel --seed 1 --duration 6 --set lidar.columns=512 --reference-map "
        "--set survey.x_min=-10 --set survey.x_max=30",
        dir_ + "/sim", dir_);
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
    // The shifted copies: the map as float64 x y z (what map.pcd is written
    // as this far out), the ground truth as TUM.
    StatusOr<std::vector<Eigen::Vector3d>> map = ReadMapPcd(dir_ + "/sim/reference_map.pcd");
    ASSERT_TRUE(map.ok()) << map.status().message();
    for (Eigen::Vector3d& p : *map) p += kUtm;
    ASSERT_TRUE(WriteMapPcd(ShiftedMap(), *map).ok());
    ASSERT_NE(ReadFile(ShiftedMap()).find("SIZE 8 8 8\n"), std::string::npos);
    StatusOr<Trajectory> gt = ReadTum(dir_ + "/sim/tunnel_gt.tum");
    ASSERT_TRUE(gt.ok());
    for (StampedPose& pose : *gt) pose.p_world_imu += kUtm;
    ASSERT_TRUE(WriteTum(ShiftedTruth(), *gt).ok());
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  static std::string ShiftedMap() { return dir_ + "/utm_map.pcd"; }
  static std::string ShiftedTruth() { return dir_ + "/utm_gt.tum"; }
  static ToolRun RunWithMap(const std::string& out, const std::string& map,
                            const std::string& truth) {
    return RunTool("run --bag " + dir_ + "/sim/tunnel.bag --config " + dir_ +
                       "/sim/tunnel.yaml --map " + map + " --initial-pose-tum " + truth +
                       " --out " + out,
                   dir_);
  }
  static inline std::string dir_;
};

TEST_F(SurveyCoordinates, ShiftedToUtmGivesTheSameTrajectoryAndDeviation) {
  const std::string local = dir_ + "/local", utm = dir_ + "/utm";
  ToolRun r = RunWithMap(local, dir_ + "/sim/reference_map.pcd", dir_ + "/sim/tunnel_gt.tum");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunWithMap(utm, ShiftedMap(), ShiftedTruth());
  ASSERT_EQ(r.exit_code, 0) << r.err;

  // trajectory.tum: the same poses, shifted.
  StatusOr<Trajectory> a = ReadTum(local + "/trajectory.tum"), b = ReadTum(utm + "/trajectory.tum");
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->size(), b->size());
  ASSERT_GT(a->size(), 40u);
  double worst_m = 0.0, worst_rad = 0.0;
  for (size_t i = 0; i < a->size(); ++i) {
    ASSERT_EQ((*a)[i].t_ns, (*b)[i].t_ns);
    worst_m = std::max(worst_m, ((*b)[i].p_world_imu - kUtm - (*a)[i].p_world_imu).norm());
    worst_rad = std::max(worst_rad, (*b)[i].q_world_imu.angularDistance((*a)[i].q_world_imu));
  }
  EXPECT_LT(worst_m, kMm);
  EXPECT_LT(worst_rad, 1e-6);
  // scans.csv positions and deviation.csv: the same values (to 1 mm).
  ExpectSameCsv(local + "/scans.csv", utm + "/scans.csv", {"x", "y", "z"});
  ExpectSameCsv(local + "/deviation.csv", utm + "/deviation.csv", {});
  // map.pcd: the same points, shifted, with the same deviation_m.
  StatusOr<PointCloudFile> ma = ReadPointCloud(local + "/map.pcd"),
                           mb = ReadPointCloud(utm + "/map.pcd");
  ASSERT_TRUE(ma.ok() && mb.ok());
  ASSERT_EQ(ma->points.size(), mb->points.size());
  EXPECT_NE(ReadFile(utm + "/map.pcd").find("SIZE 8 8 8 4 8 2 4 4\n"), std::string::npos);
  const PointCloudField *va = ma->Field("deviation_m"), *vb = mb->Field("deviation_m");
  ASSERT_TRUE(va != nullptr && vb != nullptr);
  size_t with_surface = 0;
  for (size_t i = 0; i < ma->points.size(); ++i) {
    ASSERT_LT((mb->points[i] - kUtm - ma->points[i]).norm(), kMm) << "point " << i;
    ASSERT_TRUE(Near(va->values[i], vb->values[i], kMm)) << "point " << i;
    with_surface += std::isfinite(vb->values[i]) ? 1 : 0;
  }
  EXPECT_GT(with_surface, ma->points.size() / 2);
  const nlohmann::json summary = nlohmann::json::parse(ReadFile(utm + "/summary.json"));
  EXPECT_EQ(summary["local_origin"], nlohmann::json({kUtm.x(), kUtm.y(), kUtm.z()}));
  std::printf("[ utm ] trajectory %.2g m, %.2g rad apart; %zu of %zu map points with a surface\n",
              worst_m, worst_rad, with_surface, ma->points.size());
}

// refine --map from the shifted run's trajectory in the shifted map: in the
// shifted frame, as close to the shifted truth as refine gets near zero.
TEST_F(SurveyCoordinates, RefineHeldToTheShiftedMap) {
  const std::string run = dir_ + "/utm_run", refined = dir_ + "/utm_refined";
  ToolRun r = RunWithMap(run, ShiftedMap(), ShiftedTruth());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunTool("refine --bag " + dir_ + "/sim/tunnel.bag --config " + dir_ + "/sim/tunnel.yaml" +
                  " --init " + run + "/trajectory.tum --map " + ShiftedMap() +
                  " --set refine.rounds=2 --out " + refined,
              dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double ate = testing_cli::AteNoAlign(ShiftedTruth(), refined + "/trajectory.tum", dir_);
  EXPECT_LT(ate, 0.02);
  const nlohmann::json dev = nlohmann::json::parse(ReadFile(refined + "/summary.json"))
                                 ["localization"]["deviation"];
  EXPECT_GT(dev["with_surface"].get<double>(), 0.5 * dev["map_points"].get<double>());
  EXPECT_LT(dev["median_abs_m"].get<double>(), 0.02);
  std::printf("[ utm ] refine --map: ATE (no alignment) %.4f m, median |deviation| %.4f m\n", ate,
              dev["median_abs_m"].get<double>());
}

// eval --map of the reference against itself 106 km away (beyond the search
// structure's key reach at 0.1 m voxels from the origin) and at UTM: a perfect
// match, as near zero.
TEST_F(SurveyCoordinates, EvalMapOfACloudAgainstItselfFarAway) {
  StatusOr<std::vector<Eigen::Vector3d>> map = ReadMapPcd(dir_ + "/sim/reference_map.pcd");
  ASSERT_TRUE(map.ok());
  for (Eigen::Vector3d& p : *map) p.x() += 106000.0;
  ASSERT_TRUE(WriteMapPcd(dir_ + "/far.pcd", *map).ok());
  for (const std::string& cloud : {dir_ + "/far.pcd", ShiftedMap()}) {
    const ToolRun r = RunTool("eval --map " + cloud + " --ref-map " + cloud + " --json", dir_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["completeness"].get<double>(), 1.0) << cloud;
    EXPECT_EQ(j["outlier_fraction"].get<double>(), 0.0) << cloud;
    EXPECT_LT(j["chamfer"].get<double>(), 1e-6) << cloud;
  }
}

}  // namespace
}  // namespace rvlio

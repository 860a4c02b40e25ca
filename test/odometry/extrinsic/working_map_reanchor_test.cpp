// WorkingMap re-anchoring (map.reanchor_*, online extrinsic estimation): a map
// built with a wrong extrinsic is rebuilt from the kept scans with the new one.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/math/so3.h"
#include "rvlio/odometry/scan_frontend.h"

namespace rvlio {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr TimeNs kScanPeriodNs = 100000000;

// Scan k observes its own 200 scene points (so a map point tells which scan
// put it there) from an IMU pose that sways and moves along x.
struct Scene {
  std::vector<std::vector<Eigen::Vector3d>> p_world;  // per scan
  std::vector<Pose3> T_world_imu;
};

Scene MakeScene(int scans, std::mt19937_64* rng) {
  std::uniform_real_distribution<double> u(-8.0, 8.0);
  Scene s;
  for (int k = 0; k < scans; ++k) {
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < 200; ++i) pts.emplace_back(u(*rng) + 0.3 * k, u(*rng), u(*rng));
    s.p_world.push_back(pts);
    const Eigen::Vector3d sway(0.1 * std::sin(0.7 * k), 0.1 * std::cos(0.9 * k), 0.05 * k);
    s.T_world_imu.emplace_back(so3::Exp(sway), Eigen::Vector3d(0.3 * k, 0.0, 1.0));
  }
  return s;
}

std::vector<Eigen::Vector3d> InLidar(const Pose3& T_world_lidar, const std::vector<Eigen::Vector3d>& p_world) {
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3d& p : p_world) out.push_back(T_world_lidar.Inverse() * p);
  return out;
}

// The largest distance from a stored map point to its scene point, and which
// scans contributed (a stored point is matched to the nearest scene point).
struct MapCheck {
  double max_error_m = 0.0;
  int first_scan = -1;
  size_t points = 0;
};

MapCheck Check(const WorkingMap& map, const Scene& s) {
  MapCheck c;
  map.map().ForEachPoint([&](const Eigen::Vector3d& p) {
    double best = 1e9;
    int best_scan = -1;
    for (size_t k = 0; k < s.p_world.size(); ++k)
      for (const Eigen::Vector3d& q : s.p_world[k])
        if ((q - p).norm() < best) {
          best = (q - p).norm();
          best_scan = static_cast<int>(k);
        }
    c.max_error_m = std::max(c.max_error_m, best);
    if (c.first_scan < 0 || best_scan < c.first_scan) c.first_scan = best_scan;
    ++c.points;
  });
  return c;
}

MapOptions Options(double window_s) {
  MapOptions o;
  o.min_point_distance = 0.0;
  o.max_points_per_voxel = 1000;
  o.reanchor_window = window_s;
  o.reanchor_rotation = 0.2;
  o.reanchor_translation = 0.01;
  return o;
}

const Pose3 kTrue(so3::Exp(Eigen::Vector3d(0.0, 0.0, 0.0)), Eigen::Vector3d(0.05, 0.0, 0.1));
const Pose3 kStart(so3::Exp(Eigen::Vector3d(1.0, 1.0, 1.0).normalized() * 2.0 * kDeg),
                   Eigen::Vector3d(0.08, 0.03, 0.13));

// Fills the map with scans 0..n-1 observed with kTrue but inserted with kStart.
void InsertWithStartExtrinsic(const Scene& s, WorkingMap* map) {
  for (size_t k = 0; k < s.p_world.size(); ++k)
    map->InsertScan(static_cast<TimeNs>(k) * kScanPeriodNs, s.T_world_imu[k], kStart,
                    InLidar(s.T_world_imu[k] * kTrue, s.p_world[k]));
}

TEST(WorkingMapReanchor, RebuildWithTheTrueExtrinsicRemovesTheStartErrorFromTheKeptScans) {
  std::mt19937_64 rng(3);
  const Scene s = MakeScene(30, &rng);
  WorkingMap map(Options(1.45), true);  // keeps scans 15..29 (1.4 s before the newest)
  InsertWithStartExtrinsic(s, &map);
  const MapCheck before = Check(map, s);
  EXPECT_GT(before.max_error_m, 0.1);  // 2 deg at up to ~12 m, plus 5 cm
  EXPECT_EQ(before.first_scan, 0);

  ASSERT_TRUE(map.ReanchorIfMoved(kTrue));
  EXPECT_EQ(map.rebuilds(), 1);
  const MapCheck after = Check(map, s);
  EXPECT_LT(after.max_error_m, 1e-5);  // float storage
  EXPECT_EQ(after.first_scan, 15);
  EXPECT_EQ(after.points, 15u * 200u);
  // Built with kTrue now: the same extrinsic does not rebuild again.
  EXPECT_FALSE(map.ReanchorIfMoved(kTrue));
  EXPECT_EQ(map.rebuilds(), 1);
}

TEST(WorkingMapReanchor, SmallChangesDoNotRebuildAndEitherThresholdDoes) {
  std::mt19937_64 rng(4);
  const Scene s = MakeScene(10, &rng);
  WorkingMap map(Options(20.0), true);
  InsertWithStartExtrinsic(s, &map);
  const Pose3 small_rot(kStart.R * so3::Exp(Eigen::Vector3d(0.0, 0.15 * kDeg, 0.0)), kStart.t);
  const Pose3 small_pos(kStart.R, kStart.t + Eigen::Vector3d(0.0, 0.008, 0.0));
  EXPECT_FALSE(map.ReanchorIfMoved(small_rot));
  EXPECT_FALSE(map.ReanchorIfMoved(small_pos));
  const Pose3 rot(kStart.R * so3::Exp(Eigen::Vector3d(0.0, 0.25 * kDeg, 0.0)), kStart.t);
  EXPECT_TRUE(map.ReanchorIfMoved(rot));
  const Pose3 pos(rot.R, rot.t + Eigen::Vector3d(0.012, 0.0, 0.0));
  EXPECT_TRUE(map.ReanchorIfMoved(pos));
  EXPECT_EQ(map.rebuilds(), 2);
}

TEST(WorkingMapReanchor, OffKeepsTheMapAsInserted) {
  std::mt19937_64 rng(5);
  const Scene s = MakeScene(10, &rng);
  for (const bool estimating : {false, true}) {
    // Off either way: not estimating, or a zero window (the default).
    WorkingMap map(Options(estimating ? 0.0 : 20.0), estimating);
    InsertWithStartExtrinsic(s, &map);
    const MapCheck before = Check(map, s);
    EXPECT_FALSE(map.ReanchorIfMoved(kTrue));
    EXPECT_EQ(map.rebuilds(), 0);
    const MapCheck after = Check(map, s);
    EXPECT_EQ(after.points, before.points);
    EXPECT_EQ(after.max_error_m, before.max_error_m);
  }
}

}  // namespace
}  // namespace rvlio

// Oracle: every noise-free return, moved to the world with the true IMU pose
// at its own time and the extrinsic, lies on a surface of the world; scans are
// organized rows x cols with per-column times; the noise has the configured std.
#include <cmath>

#include <gtest/gtest.h>

#include "rvlio/sim/presets.h"
#include "rvlio/sim/simulator.h"

namespace rvlio::sim {
namespace {

SimOptions Quiet(const char* preset) {
  SimOptions o = *PresetOptions(preset);
  o.lidar.range_noise = 0.0;
  return o;
}

struct ScanCheck {
  int returns = 0;
  double max_distance = 0.0;  // m, to the nearest surface
};

ScanCheck CheckScanOnSurfaces(const Simulator& sim, int64_t k) {
  const Scan scan = sim.SimulateScan(k);
  const int rows = sim.lidar().rows(), cols = sim.lidar().cols();
  ScanCheck c;
  EXPECT_EQ(scan.points.size(), static_cast<size_t>(rows) * cols);
  for (int r = 0; r < rows; ++r)
    for (int col = 0; col < cols; ++col) {
      const LidarPoint& p = scan.points[static_cast<size_t>(r) * cols + col];
      EXPECT_EQ(p.ring, r);
      EXPECT_EQ(p.t_ns, scan.t_start_ns + col * sim.lidar().period_ns() / cols);
      if (p.p_lidar.isZero()) continue;
      ++c.returns;
      const double range = p.p_lidar.cast<double>().norm();
      EXPECT_GE(range, sim.options().lidar.min_range);
      EXPECT_LE(range, sim.options().lidar.max_range);
      const Pose3 T_world_lidar = sim.TruthAt(p.t_ns).T_world_imu * sim.T_imu_lidar();
      const Eigen::Vector3d p_world = T_world_lidar * p.p_lidar.cast<double>();
      c.max_distance = std::max(c.max_distance, sim.world().DistanceToSurface(p_world));
    }
  return c;
}

// Scans at rest, right after the forward "shock" (fast attitude change), in
// the sparse part and at the far waypoint.
TEST(LidarOracle, NoiseFreeTunnelPointsLieOnTheWorldSurfaces) {
  auto sim = Simulator::Create(Quiet("tunnel"));
  ASSERT_TRUE(sim.ok()) << sim.status().message();
  const FlightTrajectory& traj = (*sim)->trajectory();
  const double rate = (*sim)->options().lidar.rate;
  for (double t :
       {0.0, traj.ArrivalTime(1) + 1.6, traj.ArrivalTime(2) - 3.0, traj.ArrivalTime(4)}) {
    const ScanCheck c = CheckScanOnSurfaces(**sim, static_cast<int64_t>(t * rate));
    EXPECT_GT(c.returns, 25000) << "t = " << t;
    EXPECT_LT(c.max_distance, 1e-3) << "t = " << t;
    std::printf("tunnel t=%.1f s: %d returns, max distance to surface %.2g m\n", t, c.returns,
                c.max_distance);
  }
}

TEST(LidarOracle, NoiseFreeHallAndCorridorPointsLieOnTheWorldSurfaces) {
  for (const char* preset : {"hall", "corridor"}) {
    auto sim = Simulator::Create(Quiet(preset));
    ASSERT_TRUE(sim.ok());
    for (int64_t k : {int64_t{5}, int64_t{180}, int64_t{330}}) {
      const ScanCheck c = CheckScanOnSurfaces(**sim, k);
      EXPECT_GT(c.returns, 15000) << preset << " scan " << k;
      EXPECT_LT(c.max_distance, 1e-3) << preset << " scan " << k;
    }
  }
}

// A point's position depends on the pose at its own column time: with the
// pose of the scan start instead, points taken during the shock miss the
// surfaces by centimetres (so the oracle above really checks per-point timing).
TEST(LidarOracle, MotionDistortionIsPresentDuringTheShock) {
  auto sim = Simulator::Create(Quiet("tunnel"));
  ASSERT_TRUE(sim.ok());
  const int64_t k = static_cast<int64_t>(((*sim)->trajectory().ArrivalTime(1) + 2.0) * 10.0);
  const Scan scan = (*sim)->SimulateScan(k);
  const Pose3 T0 = (*sim)->TruthAt(scan.t_start_ns).T_world_imu * (*sim)->T_imu_lidar();
  double worst = 0.0;
  for (const LidarPoint& p : scan.points)
    if (!p.p_lidar.isZero())
      worst = std::max(worst, (*sim)->world().DistanceToSurface(T0 * p.p_lidar.cast<double>()));
  EXPECT_GT(worst, 0.05);
}

TEST(LidarOracle, RangeNoiseHasTheConfiguredStd) {
  SimOptions noisy = *PresetOptions("tunnel");
  noisy.lidar.range_noise = 0.03;
  SimOptions quiet = noisy;
  quiet.lidar.range_noise = 0.0;
  auto a = Simulator::Create(noisy), b = Simulator::Create(quiet);
  ASSERT_TRUE(a.ok() && b.ok());
  const Scan sn = (*a)->SimulateScan(3), sq = (*b)->SimulateScan(3);
  double sum = 0, sum2 = 0;
  int n = 0;
  for (size_t i = 0; i < sn.points.size(); ++i) {
    ASSERT_EQ(sn.points[i].p_lidar.isZero(), sq.points[i].p_lidar.isZero());
    if (sq.points[i].p_lidar.isZero()) continue;
    const double d =
        sn.points[i].p_lidar.cast<double>().norm() - sq.points[i].p_lidar.cast<double>().norm();
    // Noise is along the beam: the direction does not change.
    EXPECT_NEAR(sn.points[i].p_lidar.normalized().dot(sq.points[i].p_lidar.normalized()), 1.0,
                1e-6);
    sum += d;
    sum2 += d * d;
    ++n;
  }
  ASSERT_GT(n, 20000);
  EXPECT_NEAR(sum / n, 0.0, 0.001);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.03, 0.001);
}

TEST(LidarOracle, BeamsFollowTheConfiguredFieldOfView) {
  SimOptions o = Quiet("corridor");  // OS0-32: +-45 deg
  auto sim = Simulator::Create(o);
  ASSERT_TRUE(sim.ok());
  const LidarModel& m = (*sim)->lidar();
  EXPECT_EQ(m.rows(), 32);
  EXPECT_EQ(m.cols(), 1024);
  EXPECT_EQ(m.period_ns(), 100000000);
  EXPECT_NEAR(std::asin(m.Direction(0, 0).z()) * 180 / M_PI, 45.0, 1e-9);
  EXPECT_NEAR(std::asin(m.Direction(31, 0).z()) * 180 / M_PI, -45.0, 1e-9);
  EXPECT_NEAR(m.Direction(16, 0).y(), 0.0, 1e-12);
  EXPECT_LT(m.Direction(16, 256).y(), -0.7);  // a quarter turn clockwise: -y
  const Scan s = (*sim)->SimulateScan(40);
  double max_el = -90, min_el = 90;
  for (const LidarPoint& p : s.points)
    if (!p.p_lidar.isZero()) {
      const double el = std::asin(p.p_lidar.z() / p.p_lidar.norm()) * 180 / M_PI;
      max_el = std::max(max_el, el);
      min_el = std::min(min_el, el);
    }
  EXPECT_NEAR(max_el, 45.0, 1e-3);
  EXPECT_NEAR(min_el, -45.0, 1e-3);
}

TEST(LidarOracle, RangeLimitsDropReturns) {
  SimOptions o = Quiet("tunnel");
  o.lidar.max_range = 8.0;
  o.lidar.min_range = 4.0;
  auto sim = Simulator::Create(o);
  ASSERT_TRUE(sim.ok());
  const Scan s = (*sim)->SimulateScan(300);
  int returns = 0;
  for (const LidarPoint& p : s.points)
    if (!p.p_lidar.isZero()) {
      ++returns;
      EXPECT_GE(p.p_lidar.norm(), 4.0 - 1e-4);
      EXPECT_LE(p.p_lidar.norm(), 8.0 + 1e-4);
    }
  EXPECT_GT(returns, 1000);
  EXPECT_LT(returns, 30000);
}

}  // namespace
}  // namespace rvlio::sim

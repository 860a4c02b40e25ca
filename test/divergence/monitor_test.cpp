// The divergence monitor on synthetic result streams: each check fires on
// the stream it is meant for, once per episode, and never on a healthy one.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/odometry/divergence.h"
#include "rvlio/refine/refine.h"

namespace rvlio {
namespace {

constexpr double kNoise = 0.03;     // constraints.lidar_noise, m
constexpr double kGravity = 9.81;  // imu.gravity, m/s^2
constexpr TimeNs kPeriod = 100000000;  // 10 Hz scans

// A healthy scan k of a vehicle moving at 2 m/s along x.
HealthSample Healthy(int k) {
  HealthSample s;
  s.t_ns = 1000000000 + k * kPeriod;
  s.v_world_imu = Eigen::Vector3d(2.0, 0.0, 0.0);
  s.p_world_imu = Eigen::Vector3d(0.2 * k, 0.0, 0.0);
  s.associated = k > 0;
  s.points = 1000;
  s.constraints = 700;
  s.specific_force_mps2 = 9.81 + 0.3 * std::cos(k);
  s.health.nis_per_dof = 1.5 + 0.5 * std::sin(k);
  s.health.residual_median_m = 0.02;
  s.health.residual_rms_m = 0.03;
  return s;
}

int Episodes(const DivergenceReport& r, DivergenceKind k) {
  return static_cast<int>(r.episodes[static_cast<int>(k)]);
}

TEST(DivergenceMonitor, HealthyStreamNeverFires) {
  DivergenceMonitor m(DivergenceOptions{}, kNoise, kGravity);
  for (int k = 0; k < 500; ++k) EXPECT_EQ(m.Check(Healthy(k)), 0) << "scan " << k;
  EXPECT_FALSE(m.report().detected);
  EXPECT_EQ(m.report().scans_flagged, 0);
  EXPECT_TRUE(m.report().events.empty());
}

TEST(DivergenceMonitor, SpeedFiresOncePerEpisode) {
  DivergenceMonitor m(DivergenceOptions{}, kNoise, kGravity);
  Eigen::Vector3d p(0, 0, 0);
  for (int k = 0; k < 100; ++k) {
    HealthSample s = Healthy(k);
    const bool fast = k >= 30 && k < 40;  // 10 scans at 80 m/s
    s.v_world_imu = Eigen::Vector3d(fast ? 80.0 : 2.0, 0.0, 0.0);
    p += s.v_world_imu * 0.1;
    s.p_world_imu = p;
    const uint8_t mask = m.Check(s);
    EXPECT_EQ((mask & 1u) != 0, fast) << "scan " << k;
  }
  const DivergenceReport& r = m.report();
  EXPECT_TRUE(r.detected);
  EXPECT_EQ(Episodes(r, DivergenceKind::kSpeed), 1);
  EXPECT_EQ(Episodes(r, DivergenceKind::kJump), 0);  // steps match the velocity
  EXPECT_EQ(r.first_t_ns, Healthy(30).t_ns);
  EXPECT_EQ(r.scans_flagged, 10);
  ASSERT_EQ(r.events.size(), 1u);
  EXPECT_DOUBLE_EQ(r.events[0].value, 80.0);
  EXPECT_DOUBLE_EQ(r.events[0].threshold, 50.0);
}

TEST(DivergenceMonitor, SecondEpisodeAfterAClearWindow) {
  DivergenceOptions o;
  DivergenceMonitor m(o, kNoise, kGravity);
  for (int k = 0; k < 200; ++k) {
    HealthSample s = Healthy(k);
    if (k == 50 || k == 55 || k == 150) s.v_world_imu.x() = 60.0;  // 55: same episode as 50
    s.p_world_imu = Healthy(k).p_world_imu;
    m.Check(s);
  }
  EXPECT_EQ(Episodes(m.report(), DivergenceKind::kSpeed), 2);
  EXPECT_EQ(m.report().scans_flagged, 3);
}

TEST(DivergenceMonitor, JumpBeyondVelocityAndPeriod) {
  DivergenceMonitor m(DivergenceOptions{}, kNoise, kGravity);
  for (int k = 0; k < 60; ++k) {
    HealthSample s = Healthy(k);
    if (k >= 40) s.p_world_imu.y() += 5.0;  // one 5 m sideways step at scan 40
    const uint8_t mask = m.Check(s);
    EXPECT_EQ((mask & 2u) != 0, k == 40) << "scan " << k;
  }
  ASSERT_EQ(m.report().events.size(), 1u);
  EXPECT_EQ(m.report().events[0].kind, DivergenceKind::kJump);
  // allowed = max(|v|) dt + jump_slack = 2 * 0.1 + 1.0
  EXPECT_NEAR(m.report().events[0].threshold, 1.2, 1e-9);
}

TEST(DivergenceMonitor, NisIsAWindowTestNotASingleScan) {
  DivergenceOptions o;
  DivergenceMonitor single(o, kNoise, kGravity);
  for (int k = 0; k < 100; ++k) {
    HealthSample s = Healthy(k);
    if (k == 50) s.health.nis_per_dof = 150.0;  // one bad scan: mean 150/20 + ~1.5 < 10
    single.Check(s);
  }
  EXPECT_FALSE(single.report().detected);

  DivergenceMonitor persistent(o, kNoise, kGravity);
  int first = -1;
  for (int k = 0; k < 100; ++k) {
    HealthSample s = Healthy(k);
    if (k >= 50) s.health.nis_per_dof = 30.0;
    if (persistent.Check(s) != 0 && first < 0) first = k;
  }
  EXPECT_EQ(Episodes(persistent.report(), DivergenceKind::kNis), 1);
  // The window mean passes 10 once more than ~5 of its 20 scans are at 30.
  EXPECT_GT(first, 50);
  EXPECT_LT(first, 50 + o.window_scans);
}

TEST(DivergenceMonitor, ResidualsAndInliersPersistent) {
  DivergenceMonitor m(DivergenceOptions{}, kNoise, kGravity);
  for (int k = 0; k < 100; ++k) {
    HealthSample s = Healthy(k);
    if (k >= 40) {
      s.health.residual_median_m = 0.2;  // > 2.5 * 0.03
      s.constraints = 50;                // 5% of the points
    }
    m.Check(s);
  }
  EXPECT_EQ(Episodes(m.report(), DivergenceKind::kResidual), 1);
  EXPECT_EQ(Episodes(m.report(), DivergenceKind::kInliers), 1);
  EXPECT_EQ(Episodes(m.report(), DivergenceKind::kNis), 0);
}

TEST(DivergenceMonitor, AccelerometerUnitOffByG) {
  for (const double unit : {1.0 / 9.80665, 9.80665}) {
    DivergenceMonitor m(DivergenceOptions{}, kNoise, kGravity);
    for (int k = 0; k < 60; ++k) {
      HealthSample s = Healthy(k);
      s.specific_force_mps2 *= unit;
      m.Check(s);
    }
    EXPECT_EQ(Episodes(m.report(), DivergenceKind::kGravity), 1) << unit;
    EXPECT_EQ(m.report().first_t_ns, Healthy(DivergenceOptions{}.window_scans - 1).t_ns);
  }
}

// The scans asking the prediction for a persistent rotation (the gyro and the
// LiDAR disagree: a wrong extrinsic rotation) fire once the window is full;
// one odd scan in a healthy stream does not.
TEST(DivergenceMonitor, LidarRotationAgainstTheGyroIsAWindowTest) {
  DivergenceMonitor m(DivergenceOptions{}, kNoise, kGravity);
  for (int k = 0; k < 60; ++k) {
    HealthSample s = Healthy(k);
    s.health.lidar_rotation_deg = k == 10 ? 2.0 : 0.02;  // window mean 0.12 with it
    EXPECT_EQ(m.Check(s), 0) << k;
  }
  for (int k = 60; k < 120; ++k) {
    HealthSample s = Healthy(k);
    s.health.lidar_rotation_deg = 1.5;
    m.Check(s);
  }
  EXPECT_EQ(Episodes(m.report(), DivergenceKind::kRotation), 1);
  ASSERT_FALSE(m.report().events.empty());
  EXPECT_NE(m.report().events[0].Describe().find("divergence.max_lidar_rotation_deg"),
            std::string::npos);
}

TEST(DivergenceMonitor, UnknownStatisticsAreSkippedAndNonFiniteStateFires) {
  DivergenceMonitor m(DivergenceOptions{}, kNoise, kGravity);
  for (int k = 0; k < 50; ++k) {
    HealthSample s = Healthy(k);
    s.health = ScanHealth{};  // smoother/refine without NIS, scans without update
    s.specific_force_mps2 = ScanHealth::kUnknown;
    EXPECT_EQ(m.Check(s), 0);
  }
  HealthSample bad = Healthy(50);
  bad.v_world_imu.x() = std::nan("");
  bad.p_world_imu.x() = std::nan("");
  EXPECT_EQ(m.Check(bad), 3);  // speed and jump
}

TEST(DivergenceMonitor, DisabledNeverFires) {
  DivergenceOptions o;
  o.enabled = false;
  DivergenceMonitor m(o, kNoise, kGravity);
  HealthSample s = Healthy(1);
  s.v_world_imu.x() = 1000.0;
  EXPECT_EQ(m.Check(s), 0);
  EXPECT_FALSE(m.report().detected);
}

TEST(DivergenceMonitor, DescribeNamesTheOption) {
  DivergenceEvent e{DivergenceKind::kSpeed, 0, 73.24, 50.0};
  EXPECT_EQ(e.Describe(), "speed 73.2 m/s > divergence.max_speed 50 m/s");
}

// refine's result: speed and jump from its poses and velocities, inliers
// from its last round.
RefineResult Refined(int scans) {
  RefineResult r;
  for (int k = 0; k < scans; ++k) {
    const HealthSample s = Healthy(k);
    StampedPose p;
    p.t_ns = s.t_ns;
    p.p_world_imu = s.p_world_imu;
    r.trajectory.push_back(p);
    r.v_world_imu.push_back(s.v_world_imu);
  }
  RefineRound round;
  round.points = 100000;
  round.constraints = 60000;
  r.rounds.push_back(round);
  return r;
}

TEST(DivergenceMonitor, RefineResultChecked) {
  const DivergenceOptions o;
  EXPECT_FALSE(CheckRefineResult(Refined(100), o, kNoise, kGravity).detected);

  RefineResult jumped = Refined(100);
  for (int k = 60; k < 100; ++k) jumped.trajectory[k].p_world_imu.z() += 3.0;
  const DivergenceReport j = CheckRefineResult(jumped, o, kNoise, kGravity);
  EXPECT_EQ(Episodes(j, DivergenceKind::kJump), 1);
  EXPECT_EQ(j.first_t_ns, jumped.trajectory[60].t_ns);

  RefineResult fast = Refined(100);
  fast.v_world_imu[30].x() = 70.0;
  EXPECT_EQ(Episodes(CheckRefineResult(fast, o, kNoise, kGravity), DivergenceKind::kSpeed), 1);

  RefineResult unmatched = Refined(100);
  unmatched.rounds.back().constraints = 5000;  // 5% of the points
  const DivergenceReport u = CheckRefineResult(unmatched, o, kNoise, kGravity);
  EXPECT_EQ(Episodes(u, DivergenceKind::kInliers), 1);
  EXPECT_EQ(u.scans_flagged, 100 - o.window_scans + 1);
}

TEST(DivergenceMonitor, KindNamesOfAMask) {
  EXPECT_EQ(DivergenceKindNames(0), "");
  EXPECT_EQ(DivergenceKindNames(1u | 4u), "speed+nis");
  EXPECT_EQ(DivergenceKindNames(16u), "inliers");
  EXPECT_EQ(DivergenceKindNames(32u), "gravity");
}

}  // namespace
}  // namespace rvlio

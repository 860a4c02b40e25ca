// The multirotor flight: waypoints, rest phases, smoothness, shocks, and the
// analytic derivatives (velocity, acceleration, angular rate) against finite
// differences of the pose.
#include <cmath>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "rvlio/sim/imu_sim.h"
#include "rvlio/sim/presets.h"
#include "rvlio/sim/random.h"
#include "rvlio/sim/trajectory.h"

namespace rvlio::sim {
namespace {

constexpr TimeNs kT0 = 1700000000LL * kNsPerSecond;

FlightTrajectory MakeFlight(const SimOptions& o, uint64_t seed = 1) {
  return FlightTrajectory(*ParseWaypoints(o.trajectory.waypoints), o.trajectory, o.imu.gravity, kT0,
                          seed);
}

TimeNs At(double tau) { return kT0 + SecondsToNs(tau); }

Eigen::Vector3d Log(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

TEST(Waypoints, ParseAcceptsSpacesAndRejectsBadItems) {
  auto w = ParseWaypoints(" 0,0,0 ;1.5, -2,3e0; ");
  ASSERT_TRUE(w.ok());
  ASSERT_EQ(w->size(), 2u);
  EXPECT_EQ((*w)[1], Eigen::Vector3d(1.5, -2, 3));
  for (const char* bad : {"", "1,2", "1,2,3,4", "1,x,3", "1,,3", "nan,0,0"}) {
    auto r = ParseWaypoints(bad);
    EXPECT_FALSE(r.ok()) << bad;
    if (!r.ok()) {
      EXPECT_NE(r.status().message().find("trajectory.waypoints"), std::string::npos);
    }
  }
}

// The paper's waypoints: reached in order, at rest, with level attitude.
TEST(Trajectory, TunnelFlightPassesThroughThePaperWaypoints) {
  const SimOptions o = *PresetOptions("tunnel");
  const FlightTrajectory traj = MakeFlight(o);
  const std::vector<Eigen::Vector3d> paper = {
      {0, 0, 0}, {0, 0, 2.5}, {30, 0, 2.5}, {30, 0, 4.5}, {50, 0, 4.5}};
  ASSERT_EQ(traj.waypoints().size(), paper.size());
  for (size_t i = 0; i < paper.size(); ++i) {
    const TruthState s = traj.At(At(traj.ArrivalTime(i)));
    EXPECT_LT((s.T_world_imu.t - paper[i]).norm(), 1e-9) << i;
    EXPECT_LT(s.v_world_imu.norm(), 1e-9) << i;
    EXPECT_LT(s.a_world_imu.norm(), 1e-9) << i;
    if (i > 0) {
      EXPECT_GT(traj.ArrivalTime(i), traj.ArrivalTime(i - 1) + 1.0);
    }
  }
  // ~1-2 m/s along the tunnel: 30 m in 15-30 s; the motion fits the duration.
  const double leg = traj.ArrivalTime(2) - traj.ArrivalTime(1) - o.trajectory.hover_time;
  EXPECT_GT(leg, 15.0);
  EXPECT_LT(leg, 30.0);
  EXPECT_LT(traj.MotionEnd(), o.duration);
  EXPECT_GT(traj.MotionEnd(), 40.0);
}

TEST(Trajectory, StartsAtTheOriginAtRestForTheStaticPhase) {
  const SimOptions o = *PresetOptions("tunnel");
  const FlightTrajectory traj = MakeFlight(o);
  for (double tau = 0.0; tau <= o.trajectory.static_duration; tau += 0.05) {
    const TruthState s = traj.At(At(tau));
    EXPECT_LT(s.T_world_imu.t.norm(), 1e-12);
    EXPECT_LT((s.T_world_imu.R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    EXPECT_LT(s.w_imu.norm(), 1e-12);
    const ImuSample m = ImuSimulator::Ideal(traj, At(tau));
    EXPECT_LT((m.acc_imu - Eigen::Vector3d(0, 0, o.imu.gravity)).norm(), 1e-12);
  }
  EXPECT_GT(traj.At(At(o.trajectory.static_duration + 0.5)).T_world_imu.t.z(), 0.0);
}

// v, a, jerk and the angular rate are the derivatives of p, v, a and R.
TEST(Trajectory, AnalyticDerivativesMatchFiniteDifferences) {
  for (const char* preset : {"tunnel", "hall", "loopback"}) {
    SimOptions o = *PresetOptions(preset);
    o.trajectory.yaw_amplitude = 0.3;
    const FlightTrajectory traj = MakeFlight(o);
    Rng rng(9);
    for (int i = 0; i < 300; ++i) {
      const double tau = rng.Uniform(0.0, traj.MotionEnd() + 1.0);
      const double h = 1e-4;
      const TruthState s = traj.At(At(tau));
      const TruthState sp = traj.At(At(tau + h)), sm = traj.At(At(tau - h));
      EXPECT_LT((s.v_world_imu - (sp.T_world_imu.t - sm.T_world_imu.t) / (2 * h)).norm(), 1e-5)
          << preset << tau;
      EXPECT_LT((s.a_world_imu - (sp.v_world_imu - sm.v_world_imu) / (2 * h)).norm(), 1e-4)
          << preset << tau;
      const Eigen::Vector3d w_num = Log(sm.T_world_imu.R.transpose() * sp.T_world_imu.R) / (2 * h);
      EXPECT_LT((s.w_imu - w_num).norm(), 1e-5) << preset << tau;
      Eigen::Vector3d p, v, a, j, pp, vp, ap, jp, pm, vm, am, jm;
      traj.Translation(tau, &p, &v, &a, &j);
      traj.Translation(tau + h, &pp, &vp, &ap, &jp);
      traj.Translation(tau - h, &pm, &vm, &am, &jm);
      EXPECT_LT((j - (ap - am) / (2 * h)).norm(), 2e-3) << preset << tau;
      // The body z axis is the thrust direction.
      const Eigen::Vector3d f = (s.a_world_imu + Eigen::Vector3d(0, 0, o.imu.gravity)).normalized();
      EXPECT_LT((s.T_world_imu.R.col(2) - f).norm(), 1e-12);
    }
  }
}

// Sway (trajectory.sway_amplitude): the angular rate still matches the
// finite differences of the attitude, the sway stays within its amplitude
// about each body axis, and 0 leaves the attitude exactly as without it.
TEST(Trajectory, SwayRotatesAboutAllAxesWithConsistentAngularRate) {
  SimOptions o = *PresetOptions("tunnel");
  const FlightTrajectory plain = MakeFlight(o);
  o.trajectory.sway_amplitude = 0.05;
  o.trajectory.sway_frequency = 0.8;
  const FlightTrajectory traj = MakeFlight(o);
  Rng rng(4);
  Eigen::Vector3d max_sway = Eigen::Vector3d::Zero();
  for (int i = 0; i < 300; ++i) {
    const double tau = rng.Uniform(0.0, traj.MotionEnd() + 1.0);
    const double h = 1e-4;
    const TruthState s = traj.At(At(tau)), s0 = plain.At(At(tau));
    const TruthState sp = traj.At(At(tau + h)), sm = traj.At(At(tau - h));
    const Eigen::Vector3d w_num = Log(sm.T_world_imu.R.transpose() * sp.T_world_imu.R) / (2 * h);
    EXPECT_LT((s.w_imu - w_num).norm(), 1e-5) << tau;
    EXPECT_EQ(s.T_world_imu.t, s0.T_world_imu.t);
    EXPECT_EQ(s.a_world_imu, s0.a_world_imu);
    const Eigen::Vector3d sway = Log(s0.T_world_imu.R.transpose() * s.T_world_imu.R);
    max_sway = max_sway.cwiseMax(sway.cwiseAbs());
  }
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(max_sway[k], 0.05 + 1e-9);
    EXPECT_GT(max_sway[k], 0.03);
  }
}

// C^2 acceleration: no jumps anywhere, including the ramp boundaries;
// shocks reach a few m/s^2 and tilt the vehicle.
TEST(Trajectory, AccelerationIsContinuousAndShocksAreAFewMetresPerSecondSquared) {
  const SimOptions o = *PresetOptions("tunnel");
  const FlightTrajectory traj = MakeFlight(o);
  double max_acc = 0.0, max_step = 0.0, max_tilt = 0.0, max_rate = 0.0;
  TruthState prev = traj.At(At(0.0));
  const double dt = 0.001;
  for (double tau = dt; tau < traj.MotionEnd() + 1.0; tau += dt) {
    const TruthState s = traj.At(At(tau));
    max_acc = std::max(max_acc, s.a_world_imu.norm());
    max_step = std::max(max_step, (s.a_world_imu - prev.a_world_imu).norm());
    max_tilt = std::max(max_tilt, std::acos(std::min(1.0, s.T_world_imu.R(2, 2))));
    max_rate = std::max(max_rate, s.w_imu.norm());
    prev = s;
  }
  EXPECT_GT(max_acc, 2.0);
  EXPECT_LT(max_acc, 6.0);
  EXPECT_LT(max_step, 0.05);  // jerk-limited: < 50 m/s^3
  EXPECT_GT(max_tilt, 10.0 * M_PI / 180);
  EXPECT_LT(max_tilt, 35.0 * M_PI / 180);
  EXPECT_LT(max_rate, 3.0);
  std::printf("peak acceleration %.2f m/s^2, tilt %.1f deg, angular rate %.2f rad/s\n", max_acc,
              max_tilt * 180 / M_PI, max_rate);
}

TEST(Trajectory, YawMotionIsSmallAndSeeded) {
  const SimOptions o = *PresetOptions("tunnel");
  const FlightTrajectory a = MakeFlight(o, 1), b = MakeFlight(o, 1), c = MakeFlight(o, 2);
  double max_yaw = 0.0, diff = 0.0;
  for (double tau = 0.0; tau < 50.0; tau += 0.1) {
    double ya, ra, yb, rb, yc, rc;
    a.Yaw(tau, &ya, &ra);
    b.Yaw(tau, &yb, &rb);
    c.Yaw(tau, &yc, &rc);
    EXPECT_EQ(ya, yb);
    max_yaw = std::max(max_yaw, std::abs(ya));
    diff = std::max(diff, std::abs(ya - yc));
  }
  EXPECT_LE(max_yaw, o.trajectory.yaw_amplitude + 1e-12);
  EXPECT_GT(max_yaw, 0.3 * o.trajectory.yaw_amplitude);
  EXPECT_GT(diff, 0.0);
}

TEST(Trajectory, LoopbackReturnsToTheStartPose) {
  const SimOptions o = *PresetOptions("loopback");
  const FlightTrajectory traj = MakeFlight(o);
  const TruthState end = traj.At(At(o.duration));
  EXPECT_LT(end.T_world_imu.t.norm(), 1e-9);
  double farthest = 0.0;
  for (double tau = 0; tau < o.duration; tau += 0.5)
    farthest = std::max(farthest, traj.At(At(tau)).T_world_imu.t.x());
  EXPECT_GT(farthest, 40.0);
}

// A segment shorter than speed * ramp slows down instead of overshooting.
TEST(Trajectory, ShortSegmentsStayBetweenTheirWaypoints) {
  SimOptions o = *PresetOptions("tunnel");
  o.trajectory.waypoints = "0,0,0; 0,0,0.2; 0.3,0,0.2";
  const FlightTrajectory traj = MakeFlight(o);
  for (double tau = 0; tau < traj.MotionEnd() + 1; tau += 0.01) {
    const Eigen::Vector3d p = traj.At(At(tau)).T_world_imu.t;
    EXPECT_GE(p.z(), -1e-12);
    EXPECT_LE(p.z(), 0.2 + 1e-12);
    EXPECT_GE(p.x(), -1e-12);
    EXPECT_LE(p.x(), 0.3 + 1e-12);
  }
  EXPECT_LT((traj.At(At(traj.MotionEnd())).T_world_imu.t - Eigen::Vector3d(0.3, 0, 0.2)).norm(),
            1e-12);
}

}  // namespace
}  // namespace rvlio::sim

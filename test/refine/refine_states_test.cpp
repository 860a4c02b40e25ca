// Per-scan state helpers of batch refinement: trajectory interpolation,
// finite-difference velocities, IMU slices and deskew by backward IMU
// integration from the scan-end state, against the closed-form motion.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/math/so3.h"
#include "rvlio/refine/states.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

Trajectory SampleTruth(TimeNs t0, TimeNs t1, TimeNs step) {
  Trajectory traj;
  for (TimeNs t = t0; t <= t1; t += step) {
    const PoseBlock p = test::TruePose(t);
    traj.push_back(StampedPose{t, p.p_world_imu, p.q_world_imu});
  }
  return traj;
}

RefineState TrueState(TimeNs t, const Vector3d& bg, const Vector3d& ba) {
  RefineState s;
  s.t_ns = t;
  test::TruePose(t).ToArray(s.pose.data());
  test::TrueSpeedBias(t, bg, ba).ToArray(s.speed_bias.data());
  return s;
}

TEST(RefineStates, FiniteDifferenceVelocityFollowsTheMotion) {
  const TimeNs t0 = 1000000000, t1 = 5000000000;
  const Trajectory traj = SampleTruth(t0, t1, 10000000);  // 100 Hz
  for (TimeNs t = t0 + 200000000; t < t1; t += 370000000) {
    const Vector3d v = FiniteDifferenceVelocity(traj, t, 50000000);
    EXPECT_LT((v - test::Swing(NsToSeconds(t)).v).norm(), 0.01) << t;
  }
  // Clamped at the ends: a one-sided difference, still close.
  EXPECT_LT((FiniteDifferenceVelocity(traj, t0, 50000000) - test::Swing(1.0).v).norm(), 0.05);
}

TEST(RefineStates, SliceImuCoversTheIntervalWithOneSampleEachSide) {
  std::vector<ImuSample> imu(100);
  for (int i = 0; i < 100; ++i) imu[i].t_ns = 1000 * i;
  const auto s = SliceImu(imu, 10500, 20000);
  ASSERT_FALSE(s.empty());
  EXPECT_EQ(s.front().t_ns, 10000);
  EXPECT_EQ(s.back().t_ns, 20000);  // a sample at the end itself suffices
  EXPECT_EQ(SliceImu(imu, 10500, 20500).back().t_ns, 21000);
  EXPECT_EQ(SliceImu(imu, 0, 99000).size(), 100u);
}

// Points observed along the true motion during one 0.1 s sweep, deskewed
// with the true end state (and biased IMU with matching biases), land where
// the scan-end LiDAR frame sees them.
TEST(RefineStates, DeskewWithImuMatchesTheTrueMotion) {
  const Pose3 T_imu_lidar(test::Rz(0.4) * test::Ry(-0.1), Vector3d(0.05, 0.1, -0.2));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  for (int trial = 0; trial < 4; ++trial) {
    const Vector3d bg = trial % 2 ? Vector3d(0.01, -0.02, 0.005) : Vector3d::Zero();
    const Vector3d ba = trial % 2 ? Vector3d(0.1, 0.05, -0.08) : Vector3d::Zero();
    const TimeNs t_end = 2000000000 + TimeNs{730000000} * trial, t_start = t_end - 100000000;
    const auto imu = test::SimulateImu(t_start - 20000000, t_end + 20000000, 2500000, bg, ba);
    const Pose3 T_end_lidar = test::TruePose(t_end).ToPose3() * T_imu_lidar;
    std::vector<LidarPoint> points;
    std::vector<Vector3d> expected;
    for (int i = 0; i < 200; ++i) {
      LidarPoint p;
      p.t_ns = t_start + (100000000LL * i) / 199;
      const Vector3d p_world(u(rng), u(rng), u(rng));
      const Pose3 T_lidar = test::TruePose(p.t_ns).ToPose3() * T_imu_lidar;
      p.p_lidar = (T_lidar.Inverse() * p_world).cast<float>();
      points.push_back(p);
      expected.push_back(T_end_lidar.Inverse() * (T_lidar * p.p_lidar.cast<double>()));
    }
    std::vector<Vector3d> out;
    DeskewWithImu(SliceImu(imu, t_start, t_end), TrueState(t_end, bg, ba), test::Gravity(),
                  T_imu_lidar, points, t_start, &out);
    ASSERT_EQ(out.size(), points.size());
    double worst = 0.0, raw = 0.0;
    for (size_t i = 0; i < out.size(); ++i) {
      worst = std::max(worst, (out[i] - expected[i]).norm());
      raw = std::max(raw, (points[i].p_lidar.cast<double>() - expected[i]).norm());
    }
    EXPECT_LT(worst, 1e-4) << "trial " << trial;
    EXPECT_GT(raw, 0.05) << "the motion must matter for the test to mean something";
  }
}

TEST(RefineStates, PoseDifferences) {
  const Pose3 a(test::Rz(0.1), Vector3d(1, 2, 3));
  const Pose3 b(test::Rz(0.1) * test::Rx(0.02), Vector3d(1, 2, 3.5));
  EXPECT_NEAR(RotationDifferenceDeg(a, b), 0.02 * 180.0 / M_PI, 1e-9);
  EXPECT_NEAR(TranslationDifference(a, b), 0.5, 1e-12);
}

}  // namespace
}  // namespace rvlio

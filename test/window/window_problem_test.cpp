// A tiny smoothing problem built from the factors: 5 scan states in a box
// room, IMU factors between consecutive states, one plane factor per scan,
// the first pose fixed. From perturbed initial values Ceres recovers the
// noise-free truth.
#include <memory>
#include <random>

#include <ceres/problem.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include "rvlio/factors/imu_factor.h"
#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/plane_factor.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

TEST(SmootherWindow, RecoversTheTruthFromPerturbedStates) {
  constexpr int kStates = 5;
  const TimeNs t0 = 1234567, dt = 100000000;  // 10 Hz scans
  const Vector3d bg(0.002, -0.001, 0.003), ba(0.03, -0.02, 0.01);
  const Pose3 T_imu_lidar(test::Rz(0.3) * test::Rx(0.1), Vector3d(0.1, -0.05, 0.2));
  ImuNoise noise;
  noise.gyro_noise_density = 1e-3;
  noise.accel_noise_density = 1e-2;
  noise.gyro_bias_random_walk = 1e-4;
  noise.accel_bias_random_walk = 1e-3;
  const auto samples = test::SimulateImu(t0, t0 + kStates * dt, 2500000, bg, ba);  // 400 Hz

  std::mt19937 rng(51);
  for (int trial = 0; trial < 3; ++trial) {
    ceres::Problem problem;
    std::vector<std::vector<double>> pose(kStates), sb(kStates);
    for (int k = 0; k < kStates; ++k) {
      const TimeNs t = t0 + k * dt;
      const PoseBlock truth = test::TruePose(t);
      Eigen::Matrix<double, 6, 1> d;
      d << test::RandomVector(rng, 0.03), test::RandomVector(rng, 0.15);  // ~1.7 deg, 15 cm
      pose[k] = test::ToVector(k == 0 ? truth : Plus(truth, d));
      SpeedBiasBlock init = test::TrueSpeedBias(t, Vector3d::Zero(), Vector3d::Zero());
      init.v_world_imu += test::RandomVector(rng, 0.2);  // biases start at zero
      sb[k] = test::ToVector(init);
      problem.AddResidualBlock(
          new PlaneFactor(test::BoxRoomScan(rng, truth.ToPose3(), T_imu_lidar, 300), T_imu_lidar,
                          0.02),
          nullptr, pose[k].data());
      problem.SetManifold(pose[k].data(), new PoseManifold);
    }
    for (int k = 0; k + 1 < kStates; ++k) {
      const TimeNs t = t0 + k * dt;
      problem.AddResidualBlock(
          new ImuFactor(ImuPreintegration::FromSamples(samples, t, t + dt, noise, Vector3d::Zero(),
                                                       Vector3d::Zero()),
                        test::Gravity()),
          nullptr, {pose[k].data(), sb[k].data(), pose[k + 1].data(), sb[k + 1].data()});
    }
    problem.SetParameterBlockConstant(pose[0].data());

    ceres::Solver::Options options;
    options.linear_solver_type = ceres::DENSE_SCHUR;
    options.max_num_iterations = 30;
    options.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    ASSERT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
    EXPECT_LT(summary.iterations.size(), 20u) << summary.BriefReport();

    for (int k = 0; k < kStates; ++k) {
      const TimeNs t = t0 + k * dt;
      const auto err = Minus(PoseBlock::FromArray(pose[k].data()), test::TruePose(t));
      // Measured: rotation and position errors <= 2.2e-8, velocity <= 8.5e-7,
      // gyro bias 6.2e-7, accel bias 4.8e-6 (IMU discretization at 400 Hz).
      EXPECT_LT(err.head<3>().norm(), 1e-6) << "state " << k;  // rad
      EXPECT_LT(err.tail<3>().norm(), 1e-6) << "state " << k;  // m
      const SpeedBiasBlock est = SpeedBiasBlock::FromArray(sb[k].data());
      EXPECT_LT((est.v_world_imu - test::Swing(NsToSeconds(t)).v).norm(), 1e-5) << k;
      EXPECT_LT((est.bg - bg).norm(), 1e-5) << k;
      EXPECT_LT((est.ba - ba).norm(), 1e-4) << k;
    }
  }
}

}  // namespace
}  // namespace rvlio

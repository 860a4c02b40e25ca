// The plane factor with the time offset as a parameter
// (lidar.estimate_time_offset in the smoother): residuals equal the shared
// time-offset model, Jacobians (pose, speed-bias, offset) match numeric
// differences through the manifold (Ceres' GradientChecker).
#include <algorithm>
#include <cmath>
#include <random>

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include "rvlio/constraints/time_offset_residual.h"
#include "rvlio/smoother/manifolds.h"
#include "rvlio/smoother/plane_time_offset_factor.h"
#include "smoother_test_util.h"

namespace rvlio {
namespace {

using test::RandomConstraints;

ScanTimeMotion SomeMotion() {
  ScanTimeMotion m;
  m.gyro_imu = Eigen::Vector3d(0.5, -0.8, 0.6);
  m.acc_world = Eigen::Vector3d(0.4, 1.2, -0.7);
  return m;
}

std::vector<double> SpeedBias() { return {1.1, -0.6, 0.4, 0.01, -0.02, 0.03, 0.1, 0.2, -0.1}; }

TEST(PlaneTimeOffsetFactor, ResidualsAreTheSharedModelScaledByWeight) {
  std::mt19937 rng(51);
  const ConstraintList list = RandomConstraints(rng, 30);
  const double sigma = 0.05, td_lin = 0.03, td = 0.07;
  const PoseBlock ext = test::RandomPose(rng), pose = test::RandomPose(rng);
  const PlaneTimeOffsetFactor f(list, sigma, ext.ToPose3(), SomeMotion(), td_lin);
  ASSERT_EQ(f.num_residuals(), 30);
  const std::vector<double> sb = SpeedBias();
  const Eigen::VectorXd r = test::EvaluateCost(f, {test::ToVector(pose), sb, {td}});
  FilterState x;
  x.R_world_imu = pose.ToPose3().R;
  x.p_world_imu = pose.ToPose3().t;
  x.v_world_imu = Eigen::Vector3d(sb[0], sb[1], sb[2]);
  x.R_imu_lidar = ext.ToPose3().R;
  x.t_imu_lidar = ext.ToPose3().t;
  for (size_t i = 0; i < list.size(); ++i) {
    const double expected = std::sqrt(list[i].weight) / sigma *
                            PointToPlaneResidualWithTimeOffset(list[i], x, SomeMotion(), td - td_lin);
    EXPECT_NEAR(r(i), expected, 1e-10 * std::max(1.0, std::abs(expected)));
  }
}

TEST(PlaneTimeOffsetFactor, JacobiansMatchNumericDifferences) {
  std::mt19937 rng(52);
  const PoseManifold m;
  const std::vector<const ceres::Manifold*> manifolds = {&m, nullptr, nullptr};
  for (double td : {0.03, -0.09, 0.15}) {
    const PlaneTimeOffsetFactor f(RandomConstraints(rng, 25), 0.1, test::RandomPose(rng).ToPose3(),
                                  SomeMotion(), 0.03);
    ceres::GradientChecker checker(&f, &manifolds, ceres::NumericDiffOptions());
    const auto x = test::ToVector(test::RandomPose(rng));
    const std::vector<double> sb = SpeedBias();
    const double* params[] = {x.data(), sb.data(), &td};
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(params, 1e-7, &results)) << "td " << td << ": " << results.error_log;
  }
}

}  // namespace
}  // namespace rvlio

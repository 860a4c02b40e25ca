// The alignment of a scan to a fixed reference map (odometry/reference.h).
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/math/so3.h"
#include "rvlio/odometry/reference.h"

namespace rvlio {
namespace {

// Points on a rectangular tunnel (x along the axis, 6 m wide, 5 m high,
// 60 m long) every `step_m`, with two boxes on the walls that fix x.
std::vector<Eigen::Vector3d> TunnelSurface(double step_m, bool features) {
  std::vector<Eigen::Vector3d> p;
  for (double x = -30.0; x <= 30.0; x += step_m) {
    for (double s = -3.0; s <= 3.0; s += step_m) {
      p.emplace_back(x, s, 0.0);  // floor
      p.emplace_back(x, s, 5.0);  // ceiling
    }
    for (double z = 0.0; z <= 5.0; z += step_m) {
      const bool bump_left = features && x > 2.0 && x < 4.0 && z < 2.0;
      const bool bump_right = features && x > -8.0 && x < -5.0 && z > 1.0 && z < 3.0;
      p.emplace_back(x, bump_left ? 2.5 : 3.0, z);
      p.emplace_back(x, bump_right ? -2.4 : -3.0, z);
    }
  }
  if (features)  // the boxes' end faces
    for (double z = 0.0; z <= 5.0; z += step_m)
      for (double s = 0.0; s <= 0.6; s += step_m) {
        if (z < 2.0) {
          p.emplace_back(2.0, 3.0 - s * 5.0 / 6.0, z);
          p.emplace_back(4.0, 3.0 - s * 5.0 / 6.0, z);
        }
        if (z > 1.0 && z < 3.0) {
          p.emplace_back(-8.0, -3.0 + s, z);
          p.emplace_back(-5.0, -3.0 + s, z);
        }
      }
  return p;
}

// A scan: the surface points within range of the sensor at T_ref_lidar, in
// the LiDAR frame, subsampled and with 5 mm noise.
std::vector<Eigen::Vector3d> ScanAt(const std::vector<Eigen::Vector3d>& surface,
                                    const Pose3& T_ref_lidar) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.005);
  std::uniform_real_distribution<double> keep(0.0, 1.0);
  const Pose3 T_lidar_ref = T_ref_lidar.Inverse();
  std::vector<Eigen::Vector3d> p_lidar;
  for (const Eigen::Vector3d& p : surface) {
    if ((p - T_ref_lidar.t).norm() > 20.0 || keep(rng) > 0.01) continue;
    p_lidar.push_back(T_lidar_ref * p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  }
  return p_lidar;
}

Pose3 Perturbed(const Pose3& T, const Eigen::Vector3d& dp_m, const Eigen::Vector3d& drot_deg) {
  return Pose3(T.R * so3::Exp(drot_deg * M_PI / 180.0), T.t + dp_m);
}

struct Scene {
  std::shared_ptr<const VoxelMap> reference;
  std::vector<Eigen::Vector3d> p_lidar;
  Pose3 T_ref_imu_true, T_imu_lidar;
};

Scene MakeScene(bool features) {
  Scene s;
  const LocalizationOptions options;
  s.reference = MakeReferenceMap(TunnelSurface(0.1, features), options);
  s.T_imu_lidar = Pose3(so3::Exp(Eigen::Vector3d(0.0, 0.0, 0.1)), Eigen::Vector3d(0.05, 0.0, 0.1));
  s.T_ref_imu_true = Pose3(so3::Exp(Eigen::Vector3d(0.01, -0.02, 0.3)), Eigen::Vector3d(-1.0, 0.4, 1.6));
  s.p_lidar = ScanAt(TunnelSurface(0.05, features), s.T_ref_imu_true * s.T_imu_lidar);
  return s;
}

double RotationErrorDeg(const Pose3& a, const Pose3& b) {
  return so3::Log(a.R.transpose() * b.R).norm() * 180.0 / M_PI;
}

class AlignToReferenceFrom : public ::testing::TestWithParam<std::pair<double, double>> {};

TEST_P(AlignToReferenceFrom, ConvergesFromAWrongStart) {
  const Scene s = MakeScene(true);
  const auto [dp_m, drot_deg] = GetParam();
  const Pose3 guess = Perturbed(s.T_ref_imu_true, Eigen::Vector3d(0.6, -0.6, 0.5).normalized() * dp_m,
                                Eigen::Vector3d(1.0, -1.0, 2.0).normalized() * drot_deg);
  const ReferenceAlignment a = AlignToReference(s.p_lidar, s.T_imu_lidar, *s.reference, guess,
                                                ConstraintOptions(), LocalizationOptions());
  EXPECT_LT((a.T_ref_imu.t - s.T_ref_imu_true.t).norm(), 0.01);
  EXPECT_LT(RotationErrorDeg(a.T_ref_imu, s.T_ref_imu_true), 0.1);
  EXPECT_GT(a.overlap, 0.8);
  EXPECT_NEAR(ReferenceOverlap(s.p_lidar, a.T_ref_imu, s.T_imu_lidar, *s.reference,
                               ConstraintOptions()),
              a.overlap, 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Errors, AlignToReferenceFrom,
                         ::testing::Values(std::make_pair(0.0, 0.0), std::make_pair(0.5, 3.0),
                                           std::make_pair(1.0, 5.0)));

// A featureless tunnel does not fix the pose along its axis: the alignment's
// information along x is orders of magnitude below the other axes'.
TEST(AlignToReference, FeaturelessTunnelLeavesTheAxisUninformed) {
  const Scene s = MakeScene(false);
  const ReferenceAlignment a = AlignToReference(s.p_lidar, s.T_imu_lidar, *s.reference,
                                                s.T_ref_imu_true, ConstraintOptions(),
                                                LocalizationOptions());
  const Eigen::Matrix3d info_p = a.information.block<3, 3>(3, 3);
  EXPECT_LT(info_p(0, 0), 1e-3 * info_p(1, 1));
  EXPECT_LT(info_p(0, 0), 1e-3 * info_p(2, 2));
  EXPECT_GT(std::abs(a.weakest_axis.x()), 0.99);
  EXPECT_LT(a.weakest_axis_constraints, 0.2 * LocalizationOptions().min_start_axis_constraints)
      << a.weakest_axis_constraints;
}

TEST(AlignToReference, FeaturesFixEveryAxis) {
  const Scene s = MakeScene(true);
  const ReferenceAlignment a = AlignToReference(s.p_lidar, s.T_imu_lidar, *s.reference,
                                                s.T_ref_imu_true, ConstraintOptions(),
                                                LocalizationOptions());
  EXPECT_GT(a.weakest_axis_constraints, 2.0 * LocalizationOptions().min_start_axis_constraints);
}

TEST(AlignToReference, FarFromTheReferenceThereIsNoOverlap) {
  const Scene s = MakeScene(true);
  const Pose3 far(s.T_ref_imu_true.R, s.T_ref_imu_true.t + Eigen::Vector3d(0.0, 0.0, 60.0));
  const ReferenceAlignment a = AlignToReference(s.p_lidar, s.T_imu_lidar, *s.reference, far,
                                                ConstraintOptions(), LocalizationOptions());
  EXPECT_LT(a.overlap, 0.05);
}

TEST(LocalizationOptions, RejectsRadiiTheWrongWayRound) {
  LocalizationOptions o;
  o.align_radius_min = 3.0;
  o.align_radius_max = 1.0;
  EXPECT_FALSE(o.Validate().ok());
  EXPECT_TRUE(LocalizationOptions().Validate().ok());
}

}  // namespace
}  // namespace rvlio

#include "rvlio/math/pose_interpolation.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

TEST(PoseInterpolation, InterpolatePoseIsExactAtStampsAndSlerpsBetween) {
  Trajectory traj;
  traj.push_back({1000, Vector3d(0, 0, 0), Eigen::Quaterniond::Identity()});
  traj.push_back({3000, Vector3d(2, -4, 6),
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.8, Vector3d(1, 2, 3).normalized()))});
  Pose3 T;
  ASSERT_TRUE(InterpolatePose(traj, 3000, &T));
  EXPECT_LT((T.t - Vector3d(2, -4, 6)).norm(), 1e-12);
  ASSERT_TRUE(InterpolatePose(traj, 1500, &T));
  EXPECT_LT((T.t - Vector3d(0.5, -1, 1.5)).norm(), 1e-12);
  const Vector3d w = so3::Log(T.R);
  EXPECT_NEAR(w.norm(), 0.2, 1e-9);
  EXPECT_LT((w.normalized() - Vector3d(1, 2, 3).normalized()).norm(), 1e-9);
  EXPECT_FALSE(InterpolatePose(traj, 999, &T));
  EXPECT_FALSE(InterpolatePose(traj, 3001, &T));
}

TEST(PoseInterpolation, InterpolateBetweenIsLinearInPositionAndSlerpsTheRotation) {
  const StampedPose a{10, Vector3d(1, 2, 3), Eigen::Quaterniond::Identity()};
  const StampedPose b{20, Vector3d(3, 2, 1),
                      Eigen::Quaterniond(Eigen::AngleAxisd(0.6, Vector3d::UnitZ()))};
  const StampedPose m = InterpolateBetween(a, b, 0.25);
  EXPECT_EQ(m.t_ns, 10);
  EXPECT_LT((m.p_world_imu - Vector3d(1.5, 2, 2.5)).norm(), 1e-12);
  EXPECT_NEAR(so3::Log(m.q_world_imu.toRotationMatrix()).z(), 0.15, 1e-12);
}

}  // namespace
}  // namespace rvlio

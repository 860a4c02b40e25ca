// Deskew: points measured from a moving sensor, moved to the scan-end frame,
// coincide with the same world points seen from the scan-end pose.
#include <random>

#include <gtest/gtest.h>

#include "rvlio/lidar/deskew.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

// Constant body rate and world acceleration: the motion model of the samples.
ImuPoseSample SampleAt(double t, const Eigen::Vector3d& w, const Eigen::Vector3d& a) {
  const Eigen::Vector3d v0(1.5, 0.2, -0.1);
  ImuPoseSample s;
  s.t_ns = SecondsToNs(t);
  s.R_world_imu = so3::Exp(w * t);
  s.p_world_imu = v0 * t + 0.5 * a * t * t;
  s.v_world_imu = v0 + a * t;
  s.acc_world = a;
  s.gyro_imu = w;
  return s;
}

TEST(Deskew, MovesEveryPointToTheScanEndFrame) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-10.0, 10.0), tu(0.0, 0.1);
  const Eigen::Vector3d w(0.1, -0.3, 0.8), a(0.5, -1.0, 0.2);
  std::vector<ImuPoseSample> samples;
  for (int k = 0; k <= 20; ++k) samples.push_back(SampleAt(k * 0.005, w, a));
  const Pose3 T_imu_lidar(so3::Exp(Eigen::Vector3d(0.0, 0.0, 0.1)), Eigen::Vector3d(0.05, 0, 0.1));
  const TimeNs t_end = SecondsToNs(0.1);
  const Pose3 T_world_lidar_end = Pose3(so3::Exp(w * 0.1), SampleAt(0.1, w, a).p_world_imu) *
                                  T_imu_lidar;
  std::vector<LidarPoint> points;
  std::vector<Eigen::Vector3d> expected;
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d p_world(u(rng), u(rng), u(rng));
    const double t = tu(rng);
    const ImuPoseSample truth = SampleAt(t, w, a);
    const Pose3 T_world_lidar_t = Pose3(truth.R_world_imu, truth.p_world_imu) * T_imu_lidar;
    LidarPoint p;
    p.t_ns = SecondsToNs(t);
    p.p_lidar = (T_world_lidar_t.Inverse() * p_world).cast<float>();
    points.push_back(p);
    expected.push_back(T_world_lidar_end.Inverse() * p_world);
  }
  std::vector<Eigen::Vector3d> deskewed;
  DeskewToScanEnd(samples, T_imu_lidar, points, t_end, &deskewed);
  ASSERT_EQ(deskewed.size(), points.size());
  for (size_t i = 0; i < points.size(); ++i)
    EXPECT_LT((deskewed[i] - expected[i]).norm(), 1e-5) << i;  // float storage of p_lidar
}

TEST(Deskew, ExtrapolatesBeforeTheFirstSample) {
  const Eigen::Vector3d w(0.0, 0.0, 1.0), a(0.0, 0.0, 0.0);
  std::vector<ImuPoseSample> samples = {SampleAt(0.0, w, a), SampleAt(0.05, w, a)};
  const Pose3 before = InterpolateImuPose(samples, SecondsToNs(-0.02));
  const ImuPoseSample truth = SampleAt(-0.02, w, a);
  EXPECT_LT((before.t - truth.p_world_imu).norm(), 1e-12);
  EXPECT_LT(so3::Log(before.R.transpose() * truth.R_world_imu).norm(), 1e-12);
}

}  // namespace
}  // namespace rvlio

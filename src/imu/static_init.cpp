#include "rvlio/imu/static_init.h"

#include <cmath>

#include <Eigen/Geometry>

#include "rvlio/common/check.h"

namespace rvlio {
namespace {

// Rotation that maps the measured "up" (mean specific force, IMU frame) to
// world +z with the IMU's heading kept as world yaw zero.
Eigen::Matrix3d GravityAlignedRotation(const Eigen::Vector3d& up_imu) {
  const Eigen::Matrix3d R_tilt =
      Eigen::Quaterniond::FromTwoVectors(up_imu.normalized(), Eigen::Vector3d::UnitZ())
          .toRotationMatrix();
  const Eigen::Vector3d x_world = R_tilt * Eigen::Vector3d::UnitX();
  const double yaw = std::atan2(x_world.y(), x_world.x());
  return Eigen::AngleAxisd(-yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R_tilt;
}

}  // namespace

StaticAlignment AlignStatic(const std::vector<ImuSample>& samples,
                            const StaticThresholds& thresholds) {
  RVLIO_CHECK(!samples.empty());
  Eigen::Vector3d acc_mean = Eigen::Vector3d::Zero(), gyro_mean = Eigen::Vector3d::Zero();
  for (const auto& s : samples) {
    acc_mean += s.acc_imu;
    gyro_mean += s.gyro_imu;
  }
  const double n = static_cast<double>(samples.size());
  acc_mean /= n;
  gyro_mean /= n;
  Eigen::Vector3d acc_var = Eigen::Vector3d::Zero(), gyro_var = Eigen::Vector3d::Zero();
  for (const auto& s : samples) {
    acc_var += (s.acc_imu - acc_mean).cwiseAbs2();
    gyro_var += (s.gyro_imu - gyro_mean).cwiseAbs2();
  }
  StaticAlignment a;
  a.acc_std = std::sqrt(acc_var.maxCoeff() / n);
  a.gyro_std = std::sqrt(gyro_var.maxCoeff() / n);
  a.moving = a.acc_std > thresholds.max_acc_std || a.gyro_std > thresholds.max_gyro_std;
  a.R_world_imu = GravityAlignedRotation(acc_mean);
  a.g_world = Eigen::Vector3d(0.0, 0.0, -acc_mean.norm());
  a.gyro_bias = a.moving ? Eigen::Vector3d::Zero() : gyro_mean;
  return a;
}

}  // namespace rvlio

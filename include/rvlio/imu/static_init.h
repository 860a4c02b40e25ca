#pragma once
// Static alignment from the first IMU samples: gravity direction and
// magnitude, gyroscope bias, and the world frame of docs/design.md "Conventions"
// (z up, origin and yaw of the IMU at start).
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/types.h"

namespace rvlio {

struct StaticAlignment {
  Eigen::Matrix3d R_world_imu = Eigen::Matrix3d::Identity();  // roll and pitch, zero yaw
  Eigen::Vector3d g_world = Eigen::Vector3d(0, 0, -9.81);     // m/s^2, measured magnitude
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();        // rad/s
  double acc_std = 0.0;   // m/s^2, largest per-axis std of the specific force
  double gyro_std = 0.0;  // rad/s, largest per-axis std of the angular rate
  bool moving = false;    // the samples do not look static
};

// Thresholds above which the samples are taken as moving.
struct StaticThresholds {
  double max_acc_std = 0.3;    // m/s^2
  double max_gyro_std = 0.05;  // rad/s
};

// Requires at least one sample. With a moving start the result is still the
// best estimate from the mean values, flagged `moving`.
StaticAlignment AlignStatic(const std::vector<ImuSample>& samples,
                            const StaticThresholds& thresholds = StaticThresholds());

}  // namespace rvlio

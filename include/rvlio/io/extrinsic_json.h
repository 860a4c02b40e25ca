#pragma once
// summary.json "extrinsic": the online extrinsic estimate of a run
// (odometry.h ExtrinsicReport).
#include <nlohmann/json.hpp>

#include "rvlio/odometry/odometry.h"

namespace rvlio {

// Roll, pitch, yaw (deg) of R = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Vector3d RpyDeg(const Eigen::Matrix3d& R);

// {estimated, excited_fraction, axes_excited, std_ratio, T_imu_lidar, prior, change}.
nlohmann::json ExtrinsicJson(const ExtrinsicReport& r);

}  // namespace rvlio

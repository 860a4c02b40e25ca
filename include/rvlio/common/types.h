#pragma once
// Sensor data types shared by every module. Frames are in the names.
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rvlio/common/time.h"

namespace rvlio {

// One IMU sample in the IMU frame, SI units (m/s^2, rad/s).
struct ImuSample {
  TimeNs t_ns = 0;
  Eigen::Vector3d acc_imu = Eigen::Vector3d::Zero();   // specific force, m/s^2
  Eigen::Vector3d gyro_imu = Eigen::Vector3d::Zero();  // angular rate, rad/s
};

// One LiDAR return in the LiDAR frame with its own acquisition time.
struct LidarPoint {
  Eigen::Vector3f p_lidar = Eigen::Vector3f::Zero();  // m
  float intensity = 0.0f;  // the sensor's unit: its reflectivity where it gives one (Scan::has_intensity)
  TimeNs t_ns = 0;     // absolute acquisition time of this point
  uint16_t ring = 0;   // beam index (0 when the driver has none: Scan::has_ring)
};

// One LiDAR sweep. Points are in acquisition order when the driver provides
// them so; nothing relies on it.
struct Scan {
  TimeNs t_start_ns = 0;  // earliest point time
  TimeNs t_end_ns = 0;    // latest point time: the deskew target and output stamp
  std::vector<LidarPoint> points;
  // Whether the recording's layout gives an intensity (or reflectivity) and
  // a ring per point; without, those fields of the points are 0 and the
  // output map has no such attribute (docs/outputs.md "map.pcd").
  bool has_intensity = false;
  bool has_ring = false;
};

// Adds dt_ns to every time of the scan (t_start_ns, t_end_ns, each point):
// moves a scan from one clock to another.
inline void ShiftScanTime(TimeNs dt_ns, Scan* scan) {
  scan->t_start_ns += dt_ns;
  scan->t_end_ns += dt_ns;
  for (LidarPoint& p : scan->points) p.t_ns += dt_ns;
}

// A timestamped pose (IMU in world), used by trajectories and evaluation.
struct StampedPose {
  TimeNs t_ns = 0;
  Eigen::Vector3d p_world_imu = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_world_imu = Eigen::Quaterniond::Identity();
};
using Trajectory = std::vector<StampedPose>;

}  // namespace rvlio

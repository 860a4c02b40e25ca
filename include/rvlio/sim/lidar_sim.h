#pragma once
// Spinning multi-beam LiDAR (Ouster-like). Row r (ring, 0 = top beam) has
// elevation vfov_max - r (vfov_max - vfov_min) / (beams - 1); column c has
// azimuth -2 pi c / columns (clockwise seen from above, column 0 along +x) and
// fires at scan start + c * period / columns, from the sensor pose at that
// time (real motion distortion).
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/types.h"
#include "rvlio/math/pose.h"
#include "rvlio/sim/options.h"
#include "rvlio/sim/random.h"
#include "rvlio/sim/trajectory.h"
#include "rvlio/sim/world.h"

namespace rvlio::sim {

class LidarModel {
 public:
  explicit LidarModel(const SimLidarOptions& options);
  int rows() const { return rows_; }
  int cols() const { return cols_; }
  TimeNs period_ns() const { return period_ns_; }
  TimeNs ColumnOffsetNs(int col) const { return static_cast<TimeNs>(col) * period_ns_ / cols_; }
  // Unit beam direction in the LiDAR frame.
  Eigen::Vector3d Direction(int row, int col) const {
    return Eigen::Vector3d(cos_el_[row] * cos_az_[col], cos_el_[row] * sin_az_[col], sin_el_[row]);
  }

 private:
  int rows_, cols_;
  TimeNs period_ns_;
  std::vector<double> cos_el_, sin_el_, cos_az_, sin_az_;
};

// The noise-free truth of one return (world frame): where the ray met the
// surface, the sensor position it left from, and which surface it was.
// normal_world stays zero until asked for (World::Normal; computing it for
// every return would cost more than the few kept points need).
struct SurfaceHit {
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d origin_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_world = Eigen::Vector3d::Zero();
  RayHit surface;         // the shape hit
  bool returned = false;  // false: no return (the other fields are unset)
};

// Casts one organized scan: rows x cols points, row-major by ring
// (index = row * cols + col), p_lidar = 0 for no return, every point stamped
// with its column time (also for no return). With `truth`, also the true hit
// of every point (same index; resized to rows x cols).
Scan CastScan(const World& world, const FlightTrajectory& trajectory, const LidarModel& model,
              const SimLidarOptions& options, const Pose3& T_imu_lidar, TimeNs t_start_ns,
              Rng& rng, std::vector<SurfaceHit>* truth = nullptr);

}  // namespace rvlio::sim

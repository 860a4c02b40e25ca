#include "rvlio/sim/lidar_sim.h"

#include <cmath>

#include "rvlio/common/check.h"

namespace rvlio::sim {

namespace {
constexpr double kDegToRad = M_PI / 180.0;

// Returned intensity: the surface reflectivity, fading with range.
float Intensity(float reflectivity, double range) {
  return static_cast<float>(reflectivity * 10.0 / (10.0 + range));
}
}  // namespace

LidarModel::LidarModel(const SimLidarOptions& options)
    : rows_(options.beams),
      cols_(options.columns),
      period_ns_(static_cast<TimeNs>(std::llround(1e9 / options.rate))) {
  RVLIO_CHECK(rows_ > 0 && cols_ > 0);
  for (int r = 0; r < rows_; ++r) {
    const double frac = rows_ > 1 ? static_cast<double>(r) / (rows_ - 1) : 0.5;
    const double el = (options.vfov_max - frac * (options.vfov_max - options.vfov_min)) * kDegToRad;
    cos_el_.push_back(std::cos(el));
    sin_el_.push_back(std::sin(el));
  }
  for (int c = 0; c < cols_; ++c) {
    const double az = -2.0 * M_PI * c / cols_;
    cos_az_.push_back(std::cos(az));
    sin_az_.push_back(std::sin(az));
  }
}

Scan CastScan(const World& world, const FlightTrajectory& trajectory, const LidarModel& model,
              const SimLidarOptions& options, const Pose3& T_imu_lidar, TimeNs t_start_ns,
              Rng& rng, std::vector<SurfaceHit>* truth) {
  const int rows = model.rows(), cols = model.cols();
  if (truth) truth->assign(static_cast<size_t>(rows) * cols, SurfaceHit());
  Scan scan;
  scan.has_intensity = true;
  scan.has_ring = true;
  scan.t_start_ns = t_start_ns;
  scan.t_end_ns = t_start_ns + model.ColumnOffsetNs(cols - 1);
  scan.points.resize(static_cast<size_t>(rows) * cols);
  for (int c = 0; c < cols; ++c) {
    const TimeNs t = t_start_ns + model.ColumnOffsetNs(c);
    const Pose3 T_world_lidar = trajectory.At(t).T_world_imu * T_imu_lidar;
    for (int r = 0; r < rows; ++r) {
      LidarPoint& pt = scan.points[static_cast<size_t>(r) * cols + c];
      pt.t_ns = t;
      pt.ring = static_cast<uint16_t>(r);
      const Eigen::Vector3d d_lidar = model.Direction(r, c);
      RayHit hit;
      if (!world.Raycast(T_world_lidar.t, T_world_lidar.R * d_lidar, options.max_range, &hit))
        continue;
      if (hit.range < options.min_range) continue;
      if (options.dropout > 0.0 && rng.Uniform() < options.dropout) continue;
      const double range =
          hit.range + (options.range_noise > 0.0 ? rng.Normal(options.range_noise) : 0.0);
      pt.p_lidar = (d_lidar * range).cast<float>();
      pt.intensity = Intensity(hit.reflectivity, hit.range);
      if (truth) {
        SurfaceHit& h = (*truth)[static_cast<size_t>(r) * cols + c];
        h.origin_world = T_world_lidar.t;
        h.p_world = T_world_lidar.t + (T_world_lidar.R * d_lidar) * hit.range;
        h.surface = hit;
        h.returned = true;
      }
    }
  }
  return scan;
}

}  // namespace rvlio::sim

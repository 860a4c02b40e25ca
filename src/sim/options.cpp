#include "rvlio/sim/options.h"

#include <cmath>
#include <sstream>

#include "rvlio/sim/trajectory.h"
#include "rvlio/sim/world_builder.h"

namespace rvlio {

namespace {

std::string Fmt(const Eigen::Vector3d& p) {
  std::ostringstream os;
  os << "[" << p.x() << ", " << p.y() << ", " << p.z() << "]";
  return os.str();
}

// The flight must stay inside the shell, and start at the world origin.
Status CheckWaypoints(const SimOptions& o) {
  StatusOr<std::vector<Eigen::Vector3d>> wps = sim::ParseWaypoints(o.trajectory.waypoints);
  if (!wps.ok()) return wps.status();
  if (wps->front().norm() > 1e-9)
    return Status::InvalidInput(
        "trajectory.waypoints: the first waypoint must be 0,0,0 "
        "(the world origin is the start pose), got " +
        Fmt(wps->front()));
  const sim::WorldLayout L = sim::MakeLayout(o.world);
  // Out of an open end, the flight may leave the tunnel (GNSS at the portals).
  const double far_x = o.world.end_wall ? L.x_end : L.x_end + 1e4;
  const bool open_front = o.world.layout == "tunnel" && o.world.open_entrance;
  const double near_x = open_front ? L.x_entrance - 1e4 : L.x_entrance;
  for (const Eigen::Vector3d& p : *wps) {
    const bool inside = p.x() > near_x + 0.3 && p.x() < far_x - 0.3 &&
                        std::abs(p.y() - L.y_center) < L.half_width - 0.3 &&
                        p.z() >= L.z_floor + 0.05 && p.z() < L.z_ceiling - 0.3;
    if (!inside)
      return Status::InvalidInput("trajectory.waypoints: " + Fmt(p) +
                                  " is not inside the world (keep 0.3 m from every wall)");
  }
  return Status::Ok();
}

}  // namespace

Status SimOptions::Validate() {
  Status s = ValidateFields(*this);
  if (!s.ok()) return s;
  s = extrinsics.Validate();
  if (!s.ok()) return s;
  if (lidar.beams > 1 && !(lidar.vfov_max > lidar.vfov_min))
    return Status::InvalidInput("lidar.vfov_max must be greater than lidar.vfov_min");
  if (!(lidar.max_range > lidar.min_range))
    return Status::InvalidInput("lidar.max_range must be greater than lidar.min_range");
  if (duration * lidar.rate < 1.0)
    return Status::InvalidInput("duration must cover at least one scan (1 / lidar.rate)");
  if (world.roughness_wavelength_max < world.roughness_wavelength_min)
    return Status::InvalidInput(
        "world.roughness_wavelength_max must not be below "
        "world.roughness_wavelength_min");
  if (!(survey.x_max > survey.x_min))
    return Status::InvalidInput("survey.x_max must be greater than survey.x_min");
  if (!(survey.max_range > survey.min_range))
    return Status::InvalidInput("survey.max_range must be greater than survey.min_range");
  if (world.start_height >= world.height - 0.3)
    return Status::InvalidInput("world.start_height must be below world.height - 0.3");
  if (trajectory.landing_time > 0.0 &&
      (trajectory.yaw_amplitude != 0.0 || trajectory.sway_amplitude != 0.0))
    return Status::InvalidInput(
        "trajectory.landing_time (stop-and-go) needs trajectory.yaw_amplitude 0 and "
        "trajectory.sway_amplitude 0: a landed device holds still");
  return CheckWaypoints(*this);
}

}  // namespace rvlio

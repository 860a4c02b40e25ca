#include "rvlio/sim/presets.h"

#include "rvlio/common/text.h"

namespace rvlio::sim {

namespace {

// Defaults of SimOptions are the paper's simulation (tunnel preset).
SimOptions Tunnel() {
  SimOptions o;
  o.duration = 52.0;  // the waypoints take ~49.7 s at 1.5 m/s (0.8 m/s climbing)
  o.world.clutter_length = 20.0;
  o.world.clutter_count = 45;
  o.world.sparse_spacing = 20.0;
  return o;
}

// Ouster OS0-32: +-45 deg vertical field of view, shorter range.
void UseOs0(SimLidarOptions* lidar) {
  lidar->vfov_min = -45.0;
  lidar->vfov_max = 45.0;
  lidar->max_range = 50.0;
  lidar->min_range = 0.3;
}

SimOptions Corridor() {
  SimOptions o;
  o.world.width = 5.8;
  o.world.height = 5.0;
  o.world.length = 225.5;
  o.world.start_depth = 4.0;
  o.world.clutter_length = 15.0;
  o.world.clutter_count = 25;
  o.world.sparse_spacing = 25.0;
  o.world.path_clearance = 1.0;
  UseOs0(&o.lidar);
  o.trajectory.waypoints = "0,0,0; 0,0,1.8; 40,0,1.8; 40,0,2.3; 90,0,2.3";
  o.trajectory.cruise_speed = 1.8;
  o.duration = 66.0;  // ~63.8 s of motion
  return o;
}

SimOptions Loopback() {
  SimOptions o = Corridor();
  o.trajectory.waypoints = "0,0,0; 0,0,1.8; 45,0,1.8; 45,0,2.3; 0,0,2.3; 0,0,0";
  o.duration = 71.0;  // ~68.9 s of motion, landing at the start pose
  return o;
}

SimOptions Hall() {
  SimOptions o;
  o.world.layout = "hall";
  o.world.width = 30.0;
  o.world.height = 8.0;
  o.world.length = 40.0;
  o.world.start_depth = 5.0;
  o.world.open_entrance = false;
  o.world.roughness_amplitude = 0.01;
  o.world.clutter_length = 40.0;
  o.world.clutter_count = 60;
  o.world.sparse_spacing = 0.0;
  o.world.pillar_spacing = 8.0;
  o.world.openings = 4;
  o.world.stairs = true;
  o.trajectory.waypoints = "0,0,0; 0,0,2; 25,0,2; 25,8,2; 5,8,2; 5,-6,2; 0,0,2";
  o.duration = 70.0;  // ~67.7 s of motion
  return o;
}

SimOptions Featureless() {
  SimOptions o;
  o.world.length = 1000.0;
  o.world.start_depth = 500.0;  // both ends far beyond lidar.max_range
  o.world.roughness_amplitude = 0.0;
  o.world.clutter_count = 0;
  o.world.clutter_length = 0.0;
  o.world.sparse_spacing = 0.0;
  o.duration = 52.0;
  return o;
}

// Stop-and-go over 200 m (docs/control.md): landings on floor marks every
// 50 m, a UTM-sized survey frame, the rotors' vibration in flight (what tells
// a landing from a cruise to the IMU).
SimOptions StopGo() {
  SimOptions o = Tunnel();
  o.world.length = 215.0;
  o.trajectory.waypoints = StopGoWaypoints(50.0, 4, 1.5);
  o.trajectory.yaw_amplitude = 0.0;
  o.trajectory.hover_time = 0.5;
  o.trajectory.landing_time = 4.0;
  o.imu.vibration_accel = 0.3;
  o.imu.vibration_gyro = 0.02;
  o.marks.enabled = true;
  o.marks.survey_frame = {500000.0, 5400000.0, 250.0, 30.0};
  o.marks.check_every = 2;
  o.duration = 184.0;  // ~180.4 s of motion, then the last landing
  return o;
}

// A tunnel open at both ends, flown from outside the entrance to beyond the
// far portal: GNSS fixes at both portals (docs/control.md "GNSS").
SimOptions Portals() {
  SimOptions o = Tunnel();
  o.world.length = 60.0;
  o.world.start_depth = 0.5;
  o.world.end_wall = false;
  o.trajectory.waypoints = "0,0,0; 0,0,1.5; -12,0,1.5; 72,0,1.5";
  o.marks.survey_frame = {500000.0, 5400000.0, 250.0, 30.0};
  o.gnss.enabled = true;
  o.duration = 76.0;  // ~74.3 s of motion, then a short hover beyond the far portal
  return o;
}

}  // namespace

std::string StopGoWaypoints(double spacing_m, int legs, double height_m) {
  std::string w = "0,0,0";
  const std::string h = FormatG(height_m, 10);
  for (int i = 0; i < legs; ++i) {
    const std::string x0 = FormatG(i * spacing_m, 10), x1 = FormatG((i + 1) * spacing_m, 10);
    w += "; " + x0 + ",0," + h + "; " + x1 + ",0," + h + "; " + x1 + ",0,0";
  }
  return w;
}

std::vector<std::string> PresetNames() {
  return {"tunnel", "corridor", "loopback", "hall", "featureless", "stopgo", "portals"};
}

StatusOr<SimOptions> PresetOptions(const std::string& name) {
  if (name == "tunnel") return Tunnel();
  if (name == "corridor") return Corridor();
  if (name == "loopback") return Loopback();
  if (name == "hall") return Hall();
  if (name == "featureless") return Featureless();
  if (name == "stopgo") return StopGo();
  if (name == "portals") return Portals();
  std::string list;
  for (const auto& n : PresetNames()) list += (list.empty() ? "" : ", ") + n;
  return Status::InvalidInput("unknown preset '" + name + "' (presets: " + list + ")");
}

}  // namespace rvlio::sim

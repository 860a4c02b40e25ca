#pragma once
// Options of the deterministic tunnel simulator. Presets
// (sim/presets.h) fill a SimOptions; `rvlio simulate --set key=value` edits
// it through the same Visit() list as every other options struct.
//
// Frames: world = gravity-aligned (z up), origin and yaw of the IMU at the
// start pose (docs/design.md "Conventions"). The tunnel axis is world x; the world
// geometry is placed relative to the start pose by world.start_*.
#include <array>
#include <cstdint>
#include <string>

#include "rvlio/common/options.h"
#include "rvlio/imu/options.h"
#include "rvlio/lidar/extrinsics.h"

namespace rvlio {

// A local deformation of one surface of the shell (a convergence or a
// bulge): the surface moves by
//   amplitude * c((x - x_center) / length) * c((a - across_center) / across_length),
//   c(s) = 0.5 (1 + cos(2 pi s)) for |s| < 1/2, else 0,
// along its normal, positive towards the inside of the tunnel. x is world x
// (the tunnel axis, the simulator's chainage); a is the coordinate across the
// surface: the height above the floor on a wall, the y offset from the centre
// line on the floor or ceiling; across_length 0 means uniform across the
// whole surface (a convergence). The raised cosine is smooth (C1), its
// full width at half amplitude is half its length.
struct SimDeformationOptions {
  std::string surface = "left";  // left (+y wall) | right (-y wall) | ceiling | floor
  double amplitude = 0.0;        // m, towards the inside (0: off; < 0: outwards)
  double x_center = 30.0;        // m, world x of the centre
  double length = 10.0;          // m, full extent along x
  double across_center = 2.0;    // m, height above the floor (walls) / y offset (floor, ceiling)
  double across_length = 0.0;    // m, full extent across (0: the whole surface)

  template <class V>
  void Visit(V& v) {
    v.Field("surface", surface,
            Spec()
                .Choices({"left", "right", "ceiling", "floor"})
                .Help("deformed surface: left (+y wall), right (-y wall), ceiling, floor"));
    v.Field("amplitude", amplitude,
            Spec().Unit("m").Range(-1.0, 1.0).Help(
                "displacement at the centre, positive towards the inside (0: off)"));
    v.Field("x_center", x_center,
            Spec().Unit("m").Range(-20000.0, 20000.0).Help("world x of the centre"));
    v.Field("length", length,
            Spec().Unit("m").Range(0.1, 20000.0).Help("full extent along x (raised cosine)"));
    v.Field("across_center", across_center,
            Spec().Unit("m").Range(-200.0, 200.0).Help(
                "centre across the surface: height above the floor (walls), y offset from the "
                "centre line (floor, ceiling)"));
    v.Field("across_length", across_length,
            Spec().Unit("m").Range(0.0, 400.0).Help("full extent across (0: the whole surface)"));
  }
};

// A painted band across one surface of the shell: returns from world x in
// [x_min, x_max] on it have the band's reflectivity instead of the
// surface's (80 on the walls, 40 on the floor, 60 on the ceiling), so the
// map's intensity shows a known pattern (docs/simulator.md "A painted
// band"). Off by default; draws no random number, so the rest of the world
// and every recording without it stay as they are.
struct SimBandOptions {
  std::string surface = "left";  // left (+y wall) | right (-y wall) | ceiling | floor
  double x_min = 0.0;            // m, world x where the band starts
  double x_max = 0.0;            // m, world x where it ends
  double reflectivity = 0.0;     // 0..255 (0: off)

  template <class V>
  void Visit(V& v) {
    v.Field("surface", surface,
            Spec()
                .Choices({"left", "right", "ceiling", "floor"})
                .Help("painted surface: left (+y wall), right (-y wall), ceiling, floor"));
    v.Field("x_min", x_min, Spec().Unit("m").Range(-20000.0, 20000.0).Help("world x of its start"));
    v.Field("x_max", x_max, Spec().Unit("m").Range(-20000.0, 20000.0).Help("world x of its end"));
    v.Field("reflectivity", reflectivity,
            Spec().Range(0.0, 255.0).Help("reflectivity of the paint (0: no band)"));
  }
};

// Geometry of the simulated world: a rectangular tunnel (or a closed hall)
// with rough surfaces, a feature-rich entrance region and sparse features.
struct SimWorldOptions {
  std::string layout = "tunnel";  // tunnel | hall
  double width = 10.45;           // m, extent along world y
  double height = 7.8;            // m, floor to ceiling
  double length = 100.5;          // m, extent along world x (entrance to end wall)
  double start_depth = 5.0;       // m, start pose behind the entrance (tunnel) / front wall (hall)
  double start_height = 0.3;      // m, IMU height above the floor at the start pose
  double start_lateral = 0.0;     // m, start pose y offset from the centre line
  bool open_entrance = true;      // tunnel entrance open (hall: false, a wall with openings)
  bool end_wall = true;           // closed far end
  double roughness_amplitude = 0.04;      // m, bound of the surface displacement (sum of waves)
  double roughness_wavelength_min = 0.8;  // m
  double roughness_wavelength_max = 4.0;  // m
  int roughness_components = 4;           // seeded sinusoids per surface
  double clutter_length = 15.0;  // m, feature-rich region from the entrance (hall: whole room)
  int clutter_count = 40;        // boxes, pillars and irregular blocks in that region
  double sparse_spacing = 20.0;  // m between sparse features after it (0: none)
  double path_clearance = 1.2;   // m, features keep this distance from the flight path
  double pillar_spacing = 0.0;   // m, grid of floor-to-ceiling pillars (0: none; hall)
  int openings = 0;              // doorways in the hall walls (hall only)
  bool stairs = false;           // a flight of stairs along a wall (hall only)
  SimDeformationOptions deformation;  // a convergence or bulge of one surface (default off)
  SimBandOptions band;                // a painted band of known reflectivity (default off)

  template <class V>
  void Visit(V& v) {
    v.Field("layout", layout, Spec().Choices({"tunnel", "hall"}).Help("world type"));
    v.Field("width", width, Spec().Unit("m").Range(2.0, 200.0).Help("extent along y"));
    v.Field("height", height, Spec().Unit("m").Range(2.0, 100.0).Help("floor to ceiling"));
    v.Field("length", length, Spec().Unit("m").Range(5.0, 20000.0).Help("extent along x"));
    v.Field("start_depth", start_depth,
            Spec().Unit("m").Min(0.5).Help("start pose behind the entrance along x"));
    v.Field("start_height", start_height,
            Spec().Unit("m").Range(0.05, 100.0).Help("IMU height above the floor at start"));
    v.Field("start_lateral", start_lateral,
            Spec().Unit("m").Range(-100.0, 100.0).Help("start y offset from the centre line"));
    v.Field("open_entrance", open_entrance, Spec().Help("tunnel entrance open"));
    v.Field("end_wall", end_wall, Spec().Help("closed far end"));
    v.Field("roughness_amplitude", roughness_amplitude,
            Spec().Unit("m").Range(0.0, 0.5).Help("bound of the surface height field"));
    v.Field("roughness_wavelength_min", roughness_wavelength_min,
            Spec().Unit("m").Range(0.1, 100.0));
    v.Field("roughness_wavelength_max", roughness_wavelength_max,
            Spec().Unit("m").Range(0.1, 100.0));
    v.Field("roughness_components", roughness_components,
            Spec().Range(1, 16).Help("sinusoids per surface"));
    v.Field("clutter_length", clutter_length,
            Spec().Unit("m").Range(0.0, 20000.0).Help("feature-rich region from the entrance"));
    v.Field("clutter_count", clutter_count, Spec().Range(0, 5000).Help("objects in that region"));
    v.Field("sparse_spacing", sparse_spacing,
            Spec().Unit("m").Range(0.0, 20000.0).Help("spacing of sparse features (0: none)"));
    v.Field("path_clearance", path_clearance,
            Spec().Unit("m").Range(0.0, 10.0).Help("free space around the flight path"));
    v.Field("pillar_spacing", pillar_spacing,
            Spec().Unit("m").Range(0.0, 1000.0).Help("pillar grid spacing (0: none)"));
    v.Field("openings", openings, Spec().Range(0, 32).Help("doorways in the hall walls"));
    v.Field("stairs", stairs, Spec().Help("a flight of stairs (hall)"));
    v.Section("deformation", deformation);
    v.Section("band", band);
  }
};

// Spinning LiDAR (defaults: Ouster OS1-32).
struct SimLidarOptions {
  std::string topic = "/os_cloud_node/points";
  std::string frame_id = "os_lidar";
  int beams = 32;             // rows (rings), row 0 = top beam
  double vfov_min = -22.5;    // deg, lowest beam elevation
  double vfov_max = 22.5;     // deg, highest beam elevation
  int columns = 1024;         // azimuth columns per revolution
  double rate = 10.0;         // Hz, revolutions per second
  double range_noise = 0.03;  // m, std of the Gaussian range noise
  double min_range = 0.5;     // m, closer returns are dropped
  double max_range = 100.0;   // m, farther returns are dropped
  double dropout = 0.0;       // probability of a random missing return
  double time_offset = 0.0;   // s, written LiDAR stamps = true time - clock offset
  double time_offset_drift = 0.0;  // s/s, clock offset = time_offset + drift * (t - start)

  template <class V>
  void Visit(V& v) {
    v.Field("topic", topic, Spec().Help("PointCloud2 topic written"));
    v.Field("frame_id", frame_id, Spec().Help("header frame of the clouds"));
    v.Field("beams", beams, Spec().Range(1, 512).Help("number of rings"));
    v.Field("vfov_min", vfov_min, Spec().Unit("deg").Range(-89.0, 89.0).Help("lowest elevation"));
    v.Field("vfov_max", vfov_max, Spec().Unit("deg").Range(-89.0, 89.0).Help("highest elevation"));
    v.Field("columns", columns, Spec().Range(8, 8192).Help("azimuth columns per revolution"));
    v.Field("rate", rate, Spec().Unit("Hz").Range(1.0, 100.0).Help("revolutions per second"));
    v.Field("range_noise", range_noise, Spec().Unit("m").Range(0.0, 5.0).Help("range noise std"));
    v.Field("min_range", min_range, Spec().Unit("m").Range(0.0, 1000.0));
    v.Field("max_range", max_range, Spec().Unit("m").Positive());
    v.Field("dropout", dropout, Spec().Range(0.0, 1.0).Help("probability of a missing return"));
    v.Field("time_offset", time_offset,
            Spec().Unit("s").Range(-1.0, 1.0).Help(
                "LiDAR clock error: scan stamps are written as true time - time_offset "
                "(`rvlio run --set lidar.time_offset=` the same value undoes it); not "
                "written to the emitted configuration"));
    v.Field("time_offset_drift", time_offset_drift,
            Spec().Unit("s/s").Range(-1e-3, 1e-3).Help(
                "LiDAR clock drift: the clock offset grows by this many seconds per second "
                "from time_offset at the first sample (1e-5: 10 ppm)"));
  }
};

// IMU (defaults near a consumer MEMS IMU); noise is simulated as
// discrete white noise sigma_d = sigma_c * sqrt(rate) and a bias random walk
// b_{k+1} = b_k + sigma_rw * sqrt(dt) * n_k.
struct SimImuOptions {
  std::string topic = "/imu/data";
  std::string frame_id = "imu";
  double rate = 200.0;                                        // Hz
  double gyro_noise_density = 2.0e-4;                         // rad/s/sqrt(Hz)
  double accel_noise_density = 2.0e-3;                        // m/s^2/sqrt(Hz)
  double gyro_bias_random_walk = 2.0e-5;                      // rad/s^2/sqrt(Hz)
  double accel_bias_random_walk = 2.0e-4;                     // m/s^3/sqrt(Hz)
  std::array<double, 3> gyro_bias = {0.002, -0.0015, 0.001};  // rad/s, initial bias
  std::array<double, 3> accel_bias = {0.04, -0.03, 0.05};     // m/s^2, initial bias
  double gravity = 9.81;                                      // m/s^2
  double vibration_accel = 0.0;       // m/s^2, motor vibration amplitude (0: off)
  double vibration_gyro = 0.0;        // rad/s, motor vibration amplitude (0: off)
  double vibration_frequency = 87.0;  // Hz

  template <class V>
  void Visit(V& v) {
    v.Field("topic", topic, Spec().Help("sensor_msgs/Imu topic written"));
    v.Field("frame_id", frame_id, Spec().Help("header frame of the IMU messages"));
    v.Field("rate", rate, Spec().Unit("Hz").Range(10.0, 100000.0));
    v.Field("gyro_noise_density", gyro_noise_density,
            Spec().Unit("rad/s/sqrt(Hz)").Range(0.0, 1.0));
    v.Field("accel_noise_density", accel_noise_density,
            Spec().Unit("m/s^2/sqrt(Hz)").Range(0.0, 10.0));
    v.Field("gyro_bias_random_walk", gyro_bias_random_walk,
            Spec().Unit("rad/s^2/sqrt(Hz)").Range(0.0, 1.0));
    v.Field("accel_bias_random_walk", accel_bias_random_walk,
            Spec().Unit("m/s^3/sqrt(Hz)").Range(0.0, 10.0));
    v.Field("gyro_bias", gyro_bias,
            Spec().Unit("rad/s").Range(-1.0, 1.0).Help("initial gyro bias"));
    v.Field("accel_bias", accel_bias,
            Spec().Unit("m/s^2").Range(-5.0, 5.0).Help("initial accel bias"));
    v.Field("gravity", gravity, Spec().Unit("m/s^2").Range(9.0, 10.5));
    v.Field("vibration_accel", vibration_accel,
            Spec().Unit("m/s^2").Range(0.0, 50.0).Help("motor vibration amplitude (0: off)"));
    v.Field("vibration_gyro", vibration_gyro,
            Spec().Unit("rad/s").Range(0.0, 10.0).Help("motor vibration amplitude (0: off)"));
    v.Field("vibration_frequency", vibration_frequency, Spec().Unit("Hz").Positive());
  }
};

// Multirotor-like flight through waypoints: a static phase at the first
// waypoint, then straight segments with jerk-limited speed ramps ("shocks")
// and a hover at each waypoint; attitude follows the required thrust.
struct SimTrajectoryOptions {
  // "x,y,z; x,y,z; ..." in the world frame (m); the first one must be 0,0,0.
  std::string waypoints = "0,0,0; 0,0,2.5; 30,0,2.5; 30,0,4.5; 50,0,4.5";
  double static_duration = 3.0;  // s at rest before the first motion
  double cruise_speed = 1.5;     // m/s on mostly horizontal segments
  double climb_speed = 0.8;      // m/s on mostly vertical segments
  double ramp_time = 0.8;        // s of each speed ramp (peak accel = 2.1875 speed / ramp_time)
  double hover_time = 1.5;       // s at rest at each intermediate waypoint
  double yaw_amplitude = 0.05;   // rad, small yaw motion after the static phase
  // Carried-sensor sway ("normal excitation"): a rotation Exp(phi(t)) applied
  // in the body frame on top of the thrust attitude, phi_i = sway_amplitude *
  // sin(2 pi f_i t + random phase) with f = sway_frequency * (1, 1.37, 0.71)
  // for roll, pitch, yaw, faded in with the yaw motion. 0: off (the presets).
  double sway_amplitude = 0.0;   // rad per axis
  double sway_frequency = 0.8;   // Hz of the roll component
  // Stop-and-go: a waypoint after the first at z = 0 (the take-off height:
  // standing on the floor) is a landing, where the flight rests landing_time
  // instead of hover_time. 0: off. While landed (the static phase, each
  // landing, a final landing) the motors stand still: no IMU vibration.
  double landing_time = 0.0;     // s

  template <class V>
  void Visit(V& v) {
    v.Field("waypoints", waypoints, Spec().Unit("m").Help("'x,y,z; x,y,z; ...' starting at 0,0,0"));
    v.Field("static_duration", static_duration, Spec().Unit("s").Range(0.0, 3600.0));
    v.Field("cruise_speed", cruise_speed, Spec().Unit("m/s").Range(0.05, 30.0));
    v.Field("climb_speed", climb_speed, Spec().Unit("m/s").Range(0.05, 30.0));
    v.Field("ramp_time", ramp_time,
            Spec().Unit("s").Range(0.05, 60.0).Help("duration of each speed ramp"));
    v.Field("hover_time", hover_time, Spec().Unit("s").Range(0.0, 3600.0));
    v.Field("yaw_amplitude", yaw_amplitude, Spec().Unit("rad").Range(0.0, 1.5));
    v.Field("sway_amplitude", sway_amplitude,
            Spec().Unit("rad").Range(0.0, 0.5).Help(
                "handheld/drone sway about all three body axes (0: off); "
                "0.1 at 1 Hz is the 'normal excitation' of docs/extrinsics.md"));
    v.Field("sway_frequency", sway_frequency,
            Spec().Unit("Hz").Range(0.01, 20.0).Help("sway frequency of the roll axis; "
                                                     "pitch x1.37, yaw x0.71"));
    v.Field("landing_time", landing_time,
            Spec().Unit("s").Range(0.0, 3600.0).Help(
                "stop-and-go: rest at each waypoint at z = 0 after the first (a landing) for this "
                "long, motors still (no IMU vibration); 0: off. Needs yaw_amplitude and "
                "sway_amplitude 0"));
  }
};

// A static terrestrial laser-scanner survey of the world (the reference map
// of `rvlio simulate --reference-map`, sim/survey.h): stations along the
// tunnel's centre line, dense rays over the full sphere from each, range
// noise, the union thinned to one real point per voxel.
struct SimSurveyOptions {
  bool enabled = false;          // write the reference map
  bool deformed = false;         // survey the deformed world (default: world.deformation ignored)
  double station_spacing = 5.0;  // m along x between stations (at most)
  double station_height = 1.5;   // m above the floor (raised in 0.5 m steps where a feature is)
  double angular_step = 0.3;     // deg between neighbouring rays (both directions)
  double range_noise = 0.002;    // m, std of the Gaussian range noise
  double min_range = 0.5;        // m
  double max_range = 30.0;       // m
  double voxel_size = 0.05;      // m, one point per voxel in the map
  double x_min = -1.0e4;         // m, world x range of stations and points (crop)
  double x_max = 1.0e4;          // m

  template <class V>
  void Visit(V& v) {
    v.Field("enabled", enabled, Spec().Help("write DIR/reference_map.pcd (--reference-map)"));
    v.Field("deformed", deformed,
            Spec().Help("the survey sees world.deformation (default: the undeformed world)"));
    v.Field("station_spacing", station_spacing,
            Spec().Unit("m").Range(0.5, 1000.0).Help("largest distance between stations along x"));
    v.Field("station_height", station_height,
            Spec().Unit("m").Range(0.1, 100.0).Help("scanner height above the floor"));
    v.Field("angular_step", angular_step,
            Spec().Unit("deg").Range(0.02, 5.0).Help("angle between neighbouring rays"));
    v.Field("range_noise", range_noise,
            Spec().Unit("m").Range(0.0, 0.1).Help("range noise std of the scanner"));
    v.Field("min_range", min_range, Spec().Unit("m").Range(0.0, 100.0));
    v.Field("max_range", max_range, Spec().Unit("m").Range(1.0, 2000.0));
    v.Field("voxel_size", voxel_size,
            Spec().Unit("m").Range(0.005, 1.0).Help("map thinning: one point per voxel"));
    v.Field("x_min", x_min,
            Spec().Unit("m").Range(-1.0e5, 1.0e5).Help("survey only world x >= x_min (crop)"));
    v.Field("x_max", x_max,
            Spec().Unit("m").Range(-1.0e5, 1.0e5).Help("survey only world x <= x_max (crop)"));
  }
};

// The true localizability written next to the ground truth
// (localizability.csv, docs/degeneracy_truth.md): per scan, the point-to-plane
// information of the true surface normals at the true hit points of the
// points the estimator keeps (its voxel grid, lidar.voxel_size).
struct SimLocalizabilityOptions {
  bool enabled = true;            // write localizability.csv
  double voxel_size = 0.5;        // m, the estimator's lidar.voxel_size (its default)
  double degenerate_ratio = 0.1;  // a scan is degenerate when lambda_min / lambda_max is below

  template <class V>
  void Visit(V& v) {
    v.Field("enabled", enabled, Spec().Help("write localizability.csv (the true per-scan "
                                            "localizability) next to the ground truth"));
    v.Field("voxel_size", voxel_size,
            Spec().Unit("m").Range(0.0, 10.0).Help(
                "scan voxel grid of the points that count: the estimator's lidar.voxel_size"));
    v.Field("degenerate_ratio", degenerate_ratio,
            Spec().Range(0.0, 1.0).Help(
                "a scan is degenerate when the smallest over the largest eigenvalue of its "
                "translation information sum n n^T is below this"));
  }
};

// The survey frame and the stop-and-go marks (docs/simulator.md "Survey
// frame, marks, GNSS"): p_survey = Rz(yaw) p_world + (E, N, h). The marks are
// the floor points under the IMU where the flight rests on the floor (the
// start and every landing, trajectory.landing_time), written to
// NAME_control.csv in the survey frame with Gaussian noise; the ground truth
// is also written in the survey frame (NAME_gt_survey.tum).
struct SimMarksOptions {
  bool enabled = false;  // write NAME_control.csv
  // E, N, h (m) and yaw (deg) of the world frame in the survey frame.
  std::array<double, 4> survey_frame = {0.0, 0.0, 0.0, 0.0};
  double noise_m = 0.002;  // m, std per axis of the marks' coordinates
  int check_every = 0;     // every k-th mark (1-based index % k == 0) is a check point; 0: none
  bool times = false;      // write t_start,t_end (else refine finds the rests from the IMU)

  template <class V>
  void Visit(V& v) {
    v.Field("enabled", enabled,
            Spec().Help("write NAME_control.csv: the stop-and-go marks in the survey frame"));
    v.Field("survey_frame", survey_frame,
            Spec().Range(-1e7, 1e7).Help(
                "easting, northing, height (m) and yaw (deg) of the world frame in the survey "
                "frame (rvlio simulate --survey-frame E,N,h,yaw_deg)"));
    v.Field("noise_m", noise_m,
            Spec().Unit("m").Range(0.0, 1.0).Help("std per axis of the marks' coordinates"));
    v.Field("check_every", check_every,
            Spec().Range(0, 1000).Help("every k-th mark is a check point (0: none)"));
    v.Field("times", times,
            Spec().Help("write t_start,t_end of each rest (default: refine finds them)"));
  }
};

// GNSS fixes (sensor_msgs/NavSatFix) where the flight is outside the tunnel:
// beyond the entrance (x < x_entrance - portal_margin) or beyond an open far
// end; none inside. Noise, dropouts and multipath outliers.
struct SimGnssOptions {
  bool enabled = false;
  std::string topic = "/gnss/fix";
  std::string frame_id = "gnss";
  std::string crs = "EPSG:25832";  // the projected CRS of marks.survey_frame
  double rate = 5.0;               // Hz
  std::array<double, 3> lever_arm = {0.0, 0.0, 0.1};  // m, antenna in the IMU frame
  double noise_m = 0.015;          // m, horizontal std per axis
  double noise_vertical_m = 0.03;  // m
  double dropout = 0.05;           // probability of a missing fix
  double outlier_rate = 0.02;      // probability of a multipath outlier
  double outlier_m = 3.0;          // m, horizontal offset of an outlier
  double portal_margin_m = 3.0;    // m beyond the portal before the sky is open

  template <class V>
  void Visit(V& v) {
    v.Field("enabled", enabled, Spec().Help("write NavSatFix messages outside the portals"));
    v.Field("topic", topic, Spec().Help("NavSatFix topic written"));
    v.Field("frame_id", frame_id, Spec().Help("header frame of the fixes"));
    v.Field("crs", crs,
            Spec().Help("projected CRS of the survey frame (latitude, longitude through PROJ)"));
    v.Field("rate", rate, Spec().Unit("Hz").Range(0.1, 100.0));
    v.Field("lever_arm", lever_arm,
            Spec().Unit("m").Range(-10.0, 10.0).Help("antenna position in the IMU frame"));
    v.Field("noise_m", noise_m, Spec().Unit("m").Range(0.0, 10.0).Help("horizontal std per axis"));
    v.Field("noise_vertical_m", noise_vertical_m, Spec().Unit("m").Range(0.0, 10.0));
    v.Field("dropout", dropout, Spec().Range(0.0, 1.0).Help("probability of a missing fix"));
    v.Field("outlier_rate", outlier_rate,
            Spec().Range(0.0, 1.0).Help("probability of a multipath outlier"));
    v.Field("outlier_m", outlier_m,
            Spec().Unit("m").Range(0.0, 1000.0).Help("horizontal offset of an outlier"));
    v.Field("portal_margin_m", portal_margin_m,
            Spec().Unit("m").Range(0.0, 1000.0).Help("open sky this far beyond a portal"));
  }
};

struct SimOptions {
  int64_t seed = 1;           // world seed: every random choice of the world derives from it
  // The flight's seed (trajectory yaw/sway phases, IMU noise and bias walk,
  // LiDAR noise and dropout); -1: the world seed. A second flight through the
  // same world keeps `seed` and changes this one.
  int64_t flight_seed = -1;
  double duration = 50.0;     // s of data
  double start_time = 1.7e9;  // s, absolute time of the first sample (ROS stamps)
  SimWorldOptions world;
  SimLidarOptions lidar;
  SimImuOptions imu;
  SimTrajectoryOptions trajectory;
  ExtrinsicsSection extrinsics = DefaultExtrinsics();  // LiDAR pose in the IMU frame
  SimSurveyOptions survey;
  SimLocalizabilityOptions localizability;
  SimMarksOptions marks;
  SimGnssOptions gnss;

  template <class V>
  void Visit(V& v) {
    v.Field("seed", seed, Spec().Min(0).Help("random seed (the world's; the flight's by default)"));
    v.Field("flight_seed", flight_seed,
            Spec().Min(-1).Help("seed of the flight: trajectory motion, IMU and LiDAR noise "
                                "(-1: seed); the world stays that of seed"));
    v.Field("duration", duration, Spec().Unit("s").Range(0.2, 36000.0));
    v.Field("start_time", start_time,
            Spec().Unit("s").Range(1.0, 4.0e9).Help("absolute time of the first sample"));
    v.Section("world", world);
    v.Section("lidar", lidar);
    v.Section("imu", imu);
    v.Section("trajectory", trajectory);
    v.Section("extrinsics", extrinsics);
    v.Section("survey", survey);
    v.Section("localizability", localizability);
    v.Section("marks", marks);
    v.Section("gnss", gnss);
  }

  // The seed of the flight: flight_seed, or seed when flight_seed is -1.
  uint64_t FlightSeed() const {
    return static_cast<uint64_t>(flight_seed >= 0 ? flight_seed : seed);
  }

  // Ranges of every key, then the cross-field rules (src/sim/options.cpp).
  Status Validate();

  static ExtrinsicsSection DefaultExtrinsics() {
    ExtrinsicsSection e;
    e.imu_T_lidar.translation = {0.05, 0.0, 0.1};
    return e;
  }
};

}  // namespace rvlio

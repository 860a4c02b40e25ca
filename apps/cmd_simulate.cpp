// rvlio simulate: runs the deterministic tunnel simulator (sim/) and writes
//   DIR/NAME.bag     ROS1 bag: Ouster-layout PointCloud2 + sensor_msgs/Imu
//                    (--format mcap: DIR/NAME.mcap, --format db3: DIR/NAME.db3,
//                    ROS 2 CDR messages)
//   DIR/NAME_gt.tum  true IMU pose in the world frame at 100 Hz
//   DIR/NAME.yaml    sensor configuration for `rvlio run --config`
//   DIR/reference_map.pcd  with --reference-map: a static laser-scanner
//                    survey of the world (docs/simulator.md)
//   DIR/localizability.csv  the true per-scan localizability
//                    (docs/degeneracy_truth.md; localizability.* keys)
// Argument parsing and the summary line only: SimulateRecording (rvlio/api.h)
// does the work.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "commands.h"
#include "common_options.h"
#include "interrupt.h"
#include "rvlio/api.h"
#include "rvlio/sim/presets.h"

namespace rvlio::cli {
namespace {

constexpr const char* kSimulate = "simulate";

std::string PresetList() {
  std::string list;
  for (const auto& n : sim::PresetNames()) list += (list.empty() ? "" : ", ") + n;
  return list;
}

CommandSpec SimulateSpec() {
  return {kSimulate,
          "Simulate a multirotor flight through a tunnel (or a hall) with a spinning LiDAR and an\n"
          "IMU. Writes DIR/NAME.bag (ROS1: Ouster PointCloud2 + sensor_msgs/Imu; or NAME.mcap /\n"
          "NAME.db3, ROS 2, with --format), DIR/NAME_gt.tum\n"
          "(true IMU pose in the world frame, 100 Hz) and DIR/NAME.yaml (sensor configuration for\n"
          "`rvlio run --config`). Deterministic: the same options and seed give the same files.\n"
          "--reference-map also writes DIR/reference_map.pcd, a static laser-scanner survey of\n"
          "the world in the ground truth's frame (survey.* keys; docs/simulator.md).\n"
          "DIR/localizability.csv: the true per-scan localizability (point-to-plane information\n"
          "of the true normals; localizability.* keys; docs/degeneracy_truth.md), scored by\n"
          "`rvlio eval --degeneracy`.\n"
          "Presets: " +
              PresetList() + ".",
          {{"preset", "NAME", "world, sensors and flight (default tunnel)", false, false},
           {"seed", "N", "random seed of the world (and of the flight; default 1)", false, false},
           {"flight-seed", "N",
            "seed of the flight only (motion, IMU and LiDAR noise): another flight through the "
            "same world (default: --seed)", false, false},
           {"reference-map", "", "also write DIR/reference_map.pcd (a survey of the world)", false,
            false},
           {"reference-map-only", "", "write only DIR/reference_map.pcd (no flight)", false, false},
           {"duration", "S", "seconds of data (default: the preset's)", false, false},
           {"lidar-msg", "TYPE",
            "pointcloud2 (Ouster layout, default) or livox (livox_ros_driver/CustomMsg on "
            "/livox/lidar unless sim lidar.topic is --set)", false, false},
           {"survey-frame", "E,N,h,YAW",
            "the world frame in a survey frame (m, m, m, deg): marks.survey_frame; with "
            "--set marks.enabled=true writes NAME_control.csv and NAME_gt_survey.tum "
            "(docs/control.md)",
            false, false},
           SetOption(),
           {"out", "DIR", "output directory (created if missing)", true, false},
           {"name", "NAME", "output file stem (default: the preset name)", false, false},
           {"format", "FMT", "bag (ROS1, default), mcap or db3 (ROS 2), ouster-pcap (NAME.pcap + NAME.json Ouster packets, and NAME.bag with the same quantized data), ouster-bag (NAME.bag: the packets as the ROS1 driver records them, + NAME.json)", false, false},
           {"mcap-compression", "C",
            "MCAP chunks: zstd (default), lz4, none, or unchunked", false, false}}};
}

bool ParseDouble(const std::string& text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return !text.empty() && *end == '\0' && std::isfinite(*value);
}

bool ParseInt64(const std::string& text, int64_t* value) {
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  *value = v;
  return !text.empty() && *end == '\0' && errno == 0;
}

}  // namespace

std::string ReadSeedOption(const Args& args, const std::string& name,
                           std::optional<int64_t>* seed) {
  if (!args.Has(name)) return "";
  int64_t value = 0;
  if (!ParseInt64(args.Get(name), &value) || value < 0)
    return "--" + name + " '" + args.Get(name) + "' is not a non-negative integer";
  *seed = value;
  return "";
}

std::string ReadDurationOption(const Args& args, std::optional<double>* duration_s) {
  if (!args.Has("duration")) return "";
  double value = 0.0;
  if (!ParseDouble(args.Get("duration"), &value) || value <= 0.0)
    return "--duration '" + args.Get("duration") + "' is not a positive number of seconds";
  *duration_s = value;
  return "";
}

std::string ReadSimulateArgs(const Args& args, SimulateArgs* sim) {
  sim->preset = args.Get("preset", "tunnel");
  sim->lidar_msg = args.Get("lidar-msg", "pointcloud2");
  if (std::string err = ReadSeedOption(args, "seed", &sim->seed); !err.empty()) return err;
  if (std::string err = ReadSeedOption(args, "flight-seed", &sim->flight_seed); !err.empty())
    return err;
  sim->reference_map = args.Has("reference-map");
  sim->reference_map_only = args.Has("reference-map-only");
  if (std::string err = ReadDurationOption(args, &sim->duration_s); !err.empty()) return err;
  if (args.Has("survey-frame")) {  // before --set: a --set of marks.survey_frame wins
    const std::string f = args.Get("survey-frame");
    if (std::count(f.begin(), f.end(), ',') != 3)
      return "--survey-frame '" + f + "' is not E,N,h,yaw_deg";
    sim->overrides.push_back("marks.survey_frame=[" + f + "]");
  }
  for (const std::string& set : args.GetAll("set")) sim->overrides.push_back(set);
  sim->out_dir = args.Get("out");
  sim->name = args.Get("name", sim->preset);
  sim->format = args.Get("format", "bag");
  sim->mcap_compression = args.Get("mcap-compression", "zstd");
  if (args.Has("mcap-compression") && sim->format != "mcap")
    return "--mcap-compression applies to --format mcap only";
  return "";
}

int CmdSimulate(int argc, char** argv) {
  const CommandSpec spec = SimulateSpec();
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  InterruptScope interrupt_scope;  // SIGINT/SIGTERM: stop, leave no half bag, exit 130/143
  SimulateArgs sim;
  if (std::string err = ReadSimulateArgs(args, &sim); !err.empty()) return Fail(kSimulate, err);
  return SimulateOnDisk(std::move(sim));
}

int SimulateOnDisk(SimulateArgs sim) {
  sim.stop = [] { return InterruptSignalName(); };
  // A second signal aborts at once: the writer's temporary file goes with it,
  // and the staging folder around it, and --out when this command made it.
  std::error_code exists_ec;
  const bool out_existed = std::filesystem::exists(sim.out_dir, exists_ec);
  sim.staged = [out_existed, out = sim.out_dir](const std::string& staged) {
    std::vector<std::string> made = {std::filesystem::path(staged).parent_path().string()};
    if (!out_existed) made.push_back(out);
    SetAbortRemovePath(staged + ".tmp", made);
  };
  StatusOr<SimulateResult> r = SimulateRecording(sim);
  SetAbortRemovePath("");
  if (!r.ok()) return Fail(kSimulate, r.status());
  if (r->stopped) {
    std::fprintf(stderr, "rvlio simulate: interrupted by %s; no bag written\n",
                 r->stop_reason.c_str());
    return InterruptExitCode();
  }
  std::error_code ec;
  if (!r->reference_map_path.empty())
    std::printf("rvlio simulate: reference map: %lld points from %d stations -> %s (%.1f MB) in "
                "%.1f s\n",
                static_cast<long long>(r->reference_map_points), r->reference_map_stations,
                r->reference_map_path.c_str(),
                static_cast<double>(std::filesystem::file_size(r->reference_map_path, ec)) / 1e6,
                r->reference_map_s);
  if (sim.reference_map_only) return 0;
  const double mb = static_cast<double>(std::filesystem::file_size(r->bag_path, ec)) / 1e6;
  std::printf(
      "rvlio simulate: %s: %lld scans (%dx%d), %lld IMU samples, %.1f s of data -> %s "
      "(%.1f MB) in %.1f s (%.1f s CPU)\n",
      sim.name.c_str(), static_cast<long long>(r->scans), r->rows, r->cols,
      static_cast<long long>(r->imu_samples), r->duration_s, r->bag_path.c_str(), mb, r->wall_s,
      r->cpu_s);
  if (!r->control_path.empty())
    std::printf("rvlio simulate: stop-and-go marks -> %s; ground truth in the survey frame -> %s\n",
                r->control_path.c_str(), r->gt_survey_path.c_str());
  if (!r->localizability_path.empty())
    std::printf("rvlio simulate: true localizability: %lld of %lld scans degenerate -> %s\n",
                static_cast<long long>(r->degenerate_scans), static_cast<long long>(r->scans),
                r->localizability_path.c_str());
  return 0;
}

}  // namespace rvlio::cli

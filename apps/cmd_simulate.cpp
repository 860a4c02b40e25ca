// rvlio simulate: runs the deterministic tunnel simulator (sim/) and writes
//   DIR/NAME.bag     ROS1 bag: Ouster-layout PointCloud2 + sensor_msgs/Imu
//                    (--format mcap: DIR/NAME.mcap, --format db3: DIR/NAME.db3,
//                    ROS 2 CDR messages)
//   DIR/NAME_gt.tum  true IMU pose in the world frame at 100 Hz
//   DIR/NAME.yaml    sensor configuration for `rvlio run --config`
// Argument parsing, file output and the summary line only.
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <sstream>
#include <string>

#include "commands.h"
#include "common_options.h"
#include "interrupt.h"
#include "rvlio/io/atomic_file.h"
#include "rvlio/io/config.h"
#include "rvlio/io/sensor_bag.h"
#include "rvlio/io/trajectory_io.h"
#include "rvlio/odometry/options.h"
#include "rvlio/sim/presets.h"
#include "rvlio/sim/simulator.h"

namespace rvlio::cli {
namespace {

constexpr const char* kName = "simulate";
constexpr double kGroundTruthRate = 100.0;  // Hz

std::string PresetList() {
  std::string list;
  for (const auto& n : sim::PresetNames()) list += (list.empty() ? "" : ", ") + n;
  return list;
}

CommandSpec SimulateSpec() {
  return {kName,
          "Simulate a multirotor flight through a tunnel (or a hall) with a spinning LiDAR and an\n"
          "IMU. Writes DIR/NAME.bag (ROS1: Ouster PointCloud2 + sensor_msgs/Imu; or NAME.mcap /\n"
          "NAME.db3, ROS 2, with --format), DIR/NAME_gt.tum\n"
          "(true IMU pose in the world frame, 100 Hz) and DIR/NAME.yaml (sensor configuration for\n"
          "`rvlio run --config`). Deterministic: the same options and seed give the same files.\n"
          "Presets: " +
              PresetList() + ".",
          {{"preset", "NAME", "world, sensors and flight (default tunnel)", false, false},
           {"seed", "N", "random seed (default 1)", false, false},
           {"duration", "S", "seconds of data (default: the preset's)", false, false},
           {"lidar-msg", "TYPE",
            "pointcloud2 (Ouster layout, default) or livox (livox_ros_driver/CustomMsg on "
            "/livox/lidar unless sim lidar.topic is --set)", false, false},
           SetOption(),
           {"out", "DIR", "output directory (created if missing)", true, false},
           {"name", "NAME", "output file stem (default: the preset name)", false, false},
           {"format", "FMT", "bag (ROS1, default), mcap or db3 (ROS 2)", false, false},
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

// Preset, then --seed / --duration, then each --set (applied last), then
// validation. Returns "" or the error message.
std::string ResolveOptions(const Args& args, SimOptions* options) {
  StatusOr<SimOptions> preset = sim::PresetOptions(args.Get("preset", "tunnel"));
  if (!preset.ok()) return preset.status().message();
  *options = *preset;
  const std::string lidar_msg = args.Get("lidar-msg", "pointcloud2");
  if (lidar_msg != "pointcloud2" && lidar_msg != "livox")
    return "--lidar-msg '" + lidar_msg + "' is not pointcloud2 or livox";
  if (lidar_msg == "livox") {
    options->lidar.topic = "/livox/lidar";
    options->lidar.frame_id = "livox_frame";
  }
  if (args.Has("seed") && (!ParseInt64(args.Get("seed"), &options->seed) || options->seed < 0))
    return "--seed '" + args.Get("seed") + "' is not a non-negative integer";
  if (args.Has("duration") &&
      (!ParseDouble(args.Get("duration"), &options->duration) || options->duration <= 0.0))
    return "--duration '" + args.Get("duration") + "' is not a positive number of seconds";
  for (const std::string& assignment : args.GetAll("set")) {
    Status s = ApplyOverride(*options, assignment);
    if (!s.ok()) return s.message();
  }
  Status s = options->Validate();
  return s.ok() ? "" : s.message();
}

// --format and --mcap-compression -> writer options and the file extension.
std::string ResolveFormat(const Args& args, BagWriterOptions* format, std::string* extension) {
  const std::string name = args.Get("format", "bag");
  if (name != "bag" && name != "mcap" && name != "db3")
    return "--format '" + name + "' is not one of bag, mcap, db3";
  format->format = name == "bag" ? "ros1" : name;
  *extension = "." + name;
  format->mcap_compression = args.Get("mcap-compression", "zstd");
  const std::string& c = format->mcap_compression;
  if (c != "zstd" && c != "lz4" && c != "none" && c != "unchunked")
    return "--mcap-compression '" + c + "' is not one of zstd, lz4, none, unchunked";
  if (args.Has("mcap-compression") && name != "mcap")
    return "--mcap-compression applies to --format mcap only";
  return "";
}

std::string Num(double v) {
  std::ostringstream os;
  os.precision(10);
  os << v;
  return os.str();
}

// The estimator's sensor keys (odometry/options.h) as simulated. The noise
// densities must be positive there; a noise-free simulation gets a tiny value.
std::string SensorYaml(const SimOptions& o, const std::string& name, bool livox,
                       const std::string& bag_file) {
  auto density = [](double v) { return Num(std::max(v, 1e-9)); };
  const auto& t = o.extrinsics.imu_T_lidar.translation;
  const auto& q = o.extrinsics.imu_T_lidar.rotation_xyzw;
  std::ostringstream y;
  y << "# Sensor configuration of the simulated sequence '" << name << "' (rvlio simulate, seed "
    << o.seed << ").\n# Use: rvlio run --bag " << bag_file << " --config " << name
    << ".yaml --out DIR\n"
    << "lidar:\n"
    << "  topic: " << o.lidar.topic << "\n"
    << (livox ? "  type: livox\n" : "  type: ouster\n  header_stamp: start\n")
    << "  min_range: " << Num(o.lidar.min_range) << "\n"
    << "  max_range: " << Num(o.lidar.max_range) << "\n"
    << "imu:\n"
    << "  topic: " << o.imu.topic << "\n"
    << "  gyro_noise_density: " << density(o.imu.gyro_noise_density) << "\n"
    << "  accel_noise_density: " << density(o.imu.accel_noise_density) << "\n"
    << "  gyro_bias_random_walk: " << density(o.imu.gyro_bias_random_walk) << "\n"
    << "  accel_bias_random_walk: " << density(o.imu.accel_bias_random_walk) << "\n"
    << "  gravity: " << Num(o.imu.gravity) << "\n"
    << "extrinsics:\n"
    << "  imu_T_lidar:\n"
    << "    translation: [" << Num(t[0]) << ", " << Num(t[1]) << ", " << Num(t[2]) << "]\n"
    << "    rotation_xyzw: [" << Num(q[0]) << ", " << Num(q[1]) << ", " << Num(q[2]) << ", "
    << Num(q[3]) << "]\n";
  // The resolved simulator options, as comments, so the sequence can be
  // reproduced (rvlio simulate --set KEY=VALUE for any of them).
  y << "\n# Simulator options of this sequence:\n";
  std::istringstream dump(DumpYaml(o));
  for (std::string line; std::getline(dump, line);)
    y << (line.empty() ? "#" : "#   " + line) << "\n";
  return y.str();
}

// Streams the simulation into the bag; the first write error stops the run.
// An interrupt stops it too and leaves no bag: the writer's temporary file
// (path + ".tmp") is removed when the writer goes, or by the abort of a
// second signal (interrupt.h).
Status WriteBag(const sim::Simulator& simulator, const std::string& path, bool livox,
                const BagWriterOptions& format) {
  StatusOr<std::unique_ptr<SensorBagWriter>> writer = SensorBagWriter::Create(path, format);
  if (!writer.ok()) return writer.status();
  SetAbortRemovePath(path + ".tmp");
  const SimOptions& o = simulator.options();
  Status error;
  simulator.Run(
      [&](const ImuSample& m) {
        error = (*writer)->WriteImu(o.imu.topic, o.imu.frame_id, m);
        return error.ok() && !Interrupted();
      },
      [&](const Scan& scan, int rows, int cols) {
        error = livox ? (*writer)->WriteLivoxScan(o.lidar.topic, o.lidar.frame_id, scan)
                      : (*writer)->WriteOusterScan(o.lidar.topic, o.lidar.frame_id, scan, rows, cols);
        return error.ok() && !Interrupted();
      });
  if (error.ok() && !Interrupted()) error = (*writer)->Close();
  writer->reset();  // removes the temporary file unless Close() renamed it
  SetAbortRemovePath("");
  return error;
}

std::string GroundTruthHeader(const SimOptions& o, const std::string& name) {
  return "ground truth of '" + name + "' (rvlio simulate, seed " + std::to_string(o.seed) +
         "): T_world_imu, world = gravity-aligned, origin and yaw of the IMU at start";
}

}  // namespace

int CmdSimulate(int argc, char** argv) {
  const CommandSpec spec = SimulateSpec();
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  InterruptScope interrupt_scope;  // SIGINT/SIGTERM: stop, leave no half bag, exit 130/143
  SimOptions options;
  if (std::string err = ResolveOptions(args, &options); !err.empty()) return Fail(kName, err);
  const std::string name = args.Get("name", args.Get("preset", "tunnel"));
  if (name.empty() || name.find('/') != std::string::npos)
    return Fail(kName, "--name '" + name + "' must be a plain file stem");
  const std::filesystem::path dir = args.Get("out");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    return Fail(kName, "cannot create output directory '" + dir.string() + "'" +
                           (ec ? " (" + ec.message() + ")" : ""));

  BagWriterOptions format;
  std::string extension;
  if (std::string err = ResolveFormat(args, &format, &extension); !err.empty())
    return Fail(kName, err);
  // The sensor configuration must be one that `rvlio run` accepts.
  const bool livox = args.Get("lidar-msg") == "livox";
  const std::string yaml = SensorYaml(options, name, livox, name + extension);
  OdometryOptions check;
  if (Status s = ApplyYamlText(check, yaml, name + ".yaml");
      !s.ok() || !(s = check.Validate()).ok())
    return Fail(kName, "internal: generated sensor configuration is rejected: " + s.message(), 1);

  const auto wall0 = std::chrono::steady_clock::now();
  const std::clock_t cpu0 = std::clock();
  StatusOr<std::unique_ptr<sim::Simulator>> simulator = sim::Simulator::Create(options);
  if (!simulator.ok()) return Fail(kName, simulator.status().message());
  const std::string bag_path = (dir / (name + extension)).string();
  if (Status s = WriteBag(**simulator, bag_path, livox, format); !s.ok())
    return Fail(kName, s.message(), s.exit_code());
  if (Interrupted()) {
    std::fprintf(stderr, "rvlio simulate: interrupted by %s; no bag written\n",
                 InterruptSignalName().c_str());
    return InterruptExitCode();
  }
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const double cpu_s = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;

  const Trajectory gt = (*simulator)->GroundTruth(kGroundTruthRate);
  if (Status s =
          WriteTum((dir / (name + "_gt.tum")).string(), gt, GroundTruthHeader(options, name));
      !s.ok())
    return Fail(kName, s.message(), s.exit_code());
  if (Status s = WriteFileAtomically((dir / (name + ".yaml")).string(), yaml); !s.ok())
    return Fail(kName, s.message(), s.exit_code());

  const double mb = static_cast<double>(std::filesystem::file_size(bag_path, ec)) / 1e6;
  std::printf(
      "rvlio simulate: %s: %lld scans (%dx%d), %lld IMU samples, %.1f s of data -> %s "
      "(%.1f MB) in %.1f s (%.1f s CPU)\n",
      name.c_str(), static_cast<long long>((*simulator)->scan_count()),
      (*simulator)->lidar().rows(), (*simulator)->lidar().cols(),
      static_cast<long long>((*simulator)->imu_count()), options.duration, bag_path.c_str(), mb,
      wall_s, cpu_s);
  return 0;
}

}  // namespace rvlio::cli

// `rvlio live`: RunLive (rvlio/live/live.h) with the CLI's signals and lines.
#include <unistd.h>

#include <cstdio>

#include "cli.h"
#include "commands.h"
#include "common_options.h"
#include "divergence_cli.h"
#include "interrupt.h"
#include "rvlio/live/live.h"

namespace rvlio::cli {
namespace {

// The closing line; the exit status of a run that ended by a signal.
int ReportEnd(const std::string& out_dir, const LiveResult& r) {
  const RunResult& run = r.run;
  const LiveFigures& f = r.figures;
  if (run.scans.empty()) {
    std::fprintf(stderr, "rvlio live: stopped by %s before the first scan was done; nothing written\n",
                 run.stop_reason.c_str());
    return InterruptExitCode();
  }
  std::printf("rvlio live: stopped by %s after %zu scans (%lld dropped), latency median %.2f ms "
              "p95 %.2f ms, IMU-rate odometry %.1f Hz -> %s\n",
              run.stop_reason.c_str(), run.scans.size(), static_cast<long long>(f.scans_dropped),
              f.latency_median_ms, f.latency_p95_ms, f.imu_odometry_hz, out_dir.c_str());
  return 0;
}

}  // namespace

int CmdLive(int argc, char** argv) {
  CommandSpec spec{"live",
                   "Runs the odometry on a ROS 1 or ROS 2 network: subscribes to lidar.topic and "
                   "imu.topic (point clouds, Livox CustomMsg or Ouster packets), publishes odometry (scan and IMU rate), TF, the registered scan, "
                   "path, map and status under live.topic_namespace (docs/live.md). SIGINT/SIGTERM "
                   "end it: the outputs of `run` are written to the output folder, exit 0.",
                   {{"ros1", "", "ROS 1: roscpp, the master of ROS_MASTER_URI"},
                    {"ros2", "", "ROS 2: its conventions on Cyclone DDS (docs/live.md)"},
                    {"domain-id", "N", "--ros2: DDS domain (default: live.ros2_domain_id, else $ROS_DOMAIN_ID, else 0)"},
                    ConfigOption(),
                    SetOption(),
                    {"out", "DIR", "output folder", true},
                    {"ouster-metadata", "FILE",
                     "Ouster sensor metadata JSON, needed when lidar.topic carries Ouster packets "
                     "(ouster_ros/PacketMsg, ouster_sensor_msgs/msg/PacketMsg); same as --set "
                     "lidar.ouster_metadata=FILE"},
                    {"map", "REF", "reference map (PCD or PLY, metres): localize in it (docs/survey.md)"},
                    {"initial-pose", "X,Y,Z,R,P,Y", "with --map: IMU pose in the map's frame at the first scan (m, deg)"},
                    {"initial-pose-tum", "FILE", "with --map: initial pose from a TUM file"},
                    {"quiet", "", "no progress line"},
                    AllowDivergenceOption()}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  if (args.Has("ros1") == args.Has("ros2"))
    return Fail("live", "give exactly one of --ros1 and --ros2");
  std::vector<std::string> overrides = OverridesOf(args);
  if (args.Has("domain-id")) {
    if (!args.Has("ros2")) return Fail("live", "--domain-id needs --ros2");
    long long id = 0;
    if (!ParseWholeNumber(args.Get("domain-id"), 0, 232, &id))
      return Fail("live", "--domain-id '" + args.Get("domain-id") + "' is not a DDS domain id (0..232)");
    overrides.push_back("live.ros2_domain_id=" + std::to_string(id));
  }
  std::vector<std::string> warnings;
  StatusOr<Configuration> options = LoadConfig(args.GetAll("config"), overrides, &warnings);
  if (!options.ok()) return Fail("live", options.status());
  for (const auto& w : warnings) std::fprintf(stderr, "rvlio live: warning: %s\n", w.c_str());

  LiveArgs live;
  live.middleware = args.Has("ros1") ? LiveMiddleware::kRos1 : LiveMiddleware::kRos2;
  live.options = *options;
  live.out_dir = args.Get("out");
  live.map = args.Get("map");
  live.initial_pose = args.Get("initial-pose");
  live.initial_pose_tum = args.Get("initial-pose-tum");
  live.stop = [] { return InterruptSignalName(); };
  // For an operator at a terminal (as the progress lines of run): an error
  // later stays the only line a script sees.
  const bool tell = !args.Has("quiet") && ::isatty(STDERR_FILENO);
  live.on_ready = [tell](const std::string& origin) {
    if (tell) std::fprintf(stderr, "rvlio live: listening on %s (Ctrl-C ends it)\n", origin.c_str());
  };
  size_t divergence_warned = 0;
  live.progress = [&divergence_warned](const RunProgress& p) {
    WarnDivergence("live", *p.divergence, &divergence_warned);
  };
  InterruptScope interrupt_scope;  // SIGINT/SIGTERM end the run: outputs written
  StatusOr<LiveResult> result = RunLive(live);
  if (!result.ok()) return Fail("live", result.status());
  const RunResult& run = result->run;
  if (!run.read_error.ok())
    return Fail("live", run.read_error.message() + " (outputs hold the scans before it)");
  for (const auto& w : run.warnings) std::fprintf(stderr, "rvlio live: warning: %s\n", w.c_str());
  const int rc = ReportEnd(live.out_dir, *result);
  if (rc == 0 && run.divergence.detected)
    return FinishDiverged("live", run.divergence, live.out_dir, args.Has("allow-divergence"));
  return rc;
}

}  // namespace rvlio::cli

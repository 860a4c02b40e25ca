#include <cstdio>

#include "commands.h"
#include "common_options.h"
#include "interrupt.h"
#include "divergence_cli.h"
#include "run_pipeline.h"
#include "window_options.h"

namespace rvlio::cli {

int CmdRun(int argc, char** argv) {
  CommandSpec spec{"run",
                   "Runs the odometry on a ROS1 bag and writes trajectory.tum, map.pcd, scans.csv "
                   "and summary.json to the output folder.",
                   {{"bag", "FILE", "ROS1 bag with LiDAR and IMU topics", true},
                    ConfigOption(),
                    SetOption(),
                    {"out", "DIR", "output folder", true},
                    {"quiet", "", "no progress line"},
                    StartOption(),
                    DurationOption(),
                    AllowDivergenceOption()}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  RunRequest req{args.Get("bag"), args.Get("out"), args.GetAll("config"), args.GetAll("set"),
                 args.Has("quiet"), args.Has("allow-divergence"), ReadWindow()};
  if (std::string err = ParseWindow(args, &req.window); !err.empty()) return Fail("run", err);
  RunOutcome outcome;
  InterruptScope interrupt_scope;  // SIGINT/SIGTERM: write what is done, exit 130/143
  const int rc = RunOdometryOnBag(req, &outcome);
  if (rc == 0)
    std::printf("rvlio run: %d scans, per-scan median %.2f ms, %.1fx real time -> %s\n",
                outcome.scans, outcome.median_ms, outcome.real_time_factor, req.out_dir.c_str());
  return rc;
}

}  // namespace rvlio::cli

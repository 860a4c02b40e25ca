#include <cstdio>

#include "rvlio/formats/control_file.h"

#include "commands.h"
#include "common_options.h"
#include "interrupt.h"
#include "run_pipeline.h"
#include "time_range_options.h"

namespace rvlio::cli {

int CmdRun(int argc, char** argv) {
  CommandSpec spec{"run",
                   "Runs the odometry on a recording (ROS1 or ROS 2 bag) and writes trajectory.tum, "
                   "map.pcd, scans.csv and summary.json to the output folder (and "
                   "trajectory.partial.tum while it runs). SIGINT/SIGTERM write the outputs of the "
                   "scans done and exit 130/143.",
                   {{"bag", "PATH", "recording with LiDAR and IMU topics: ROS1 .bag, ROS 2 .db3, .mcap or bag folder; or Ouster packets (.pcap + metadata JSON, packet bag)", true},
                    ConfigOption(),
                    SetOption(),
                    OusterMetadataOption(),
                    {"out", "DIR", "output folder", true},
                    StartOption(),
                    DurationOption(),
                    {"map", "REF", "reference map (PCD or PLY, metres): localize in it; outputs in its frame (docs/survey.md)"},
                    {"initial-pose", "X,Y,Z,R,P,Y", "with --map: IMU pose in the map's frame at the first scan (m, deg; R = Rz Ry Rx)"},
                    {"initial-pose-tum", "FILE", "with --map: initial pose from a TUM file (one line, or interpolated at the first scan)"},
                    {"control", "FILE", "control file: checked, then left to `rvlio refine --control FILE` (the online backends do not use it; docs/control.md)"},
                    {"quiet", "", "no progress line"},
                    AllowDivergenceOption()}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  RunRequest req{args.Get("bag"),     args.Get("out"),
                 args.GetAll("config"), OverridesOf(args),
                 args.Has("quiet"),   args.Has("allow-divergence"),
                 ReadWindow(),        args.Get("map"),
                 args.Get("initial-pose"), args.Get("initial-pose-tum")};
  if (std::string err = ParseWindow(args, &req.window); !err.empty()) return Fail("run", err);
  if (args.Has("control")) {
    // The online backends do not take control points (docs/control.md "Online
    // backends"): the file is checked now, so that a bad one is found before
    // the flight is processed, and refine ties the trajectory to it.
    StatusOr<std::vector<ControlRow>> rows = ReadControlFile(args.Get("control"));
    if (!rows.ok()) return Fail("run", rows.status());
    std::fprintf(stderr,
                 "rvlio run: note: --control is used by refine: this run's outputs stay in its own "
                 "frame; tie them to the %zu control file rows with `rvlio refine --init "
                 "OUT/trajectory.tum --control %s`\n",
                 rows->size(), args.Get("control").c_str());
  }
  RunOutcome outcome;
  InterruptScope interrupt_scope;  // SIGINT/SIGTERM: write what is done, exit 130/143
  const int rc = RunOdometryOnBag(req, &outcome);
  if (rc == 0)
    std::printf("rvlio run: %d scans, per-scan median %.2f ms, %.1fx real time -> %s\n",
                outcome.scans, outcome.median_ms, outcome.real_time_factor, req.out_dir.c_str());
  return rc;
}

}  // namespace rvlio::cli

#pragma once
// `rvlio run` and `rvlio refine` as functions, so that demo and compare reuse
// them in-process: RunRecording / RefineRecording (rvlio/api.h) with the
// command's signals, progress and round lines and messages.
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "rvlio/api.h"
#include "rvlio/outputs/output_stage.h"
#include "rvlio/formats/sensor_bag.h"
#include "rvlio/formats/sensor_stream.h"
#include "rvlio/outputs/summary_json.h"

namespace rvlio::cli {

struct RunRequest {
  std::string bag;
  std::string out_dir;
  std::vector<std::string> config_files;
  std::vector<std::string> overrides;  // --set key=value
  bool quiet = false;                  // no progress line even on a terminal
  bool allow_divergence = false;       // exit 0 even if the divergence monitor fired
  ReadWindow window;                   // --start / --duration
  std::string map;                     // --map: localize in this reference map
  std::string initial_pose;            // --initial-pose x,y,z,roll_deg,pitch_deg,yaw_deg
  std::string initial_pose_tum;        // --initial-pose-tum FILE
};

struct RunOutcome {
  int scans = 0;
  double median_ms = 0.0;
  double real_time_factor = 0.0;
  bool diverged = false;  // the divergence monitor fired (summary.json divergence)
};

// Reads the bag, runs the odometry and writes the outputs of docs/design.md
// "The command-line contract". Returns the exit status; errors are printed as one line.
// While it runs, trajectory.partial.tum in the output folder receives each
// pose as it is estimated (removed at an orderly end). Under an InterruptScope
// (interrupt.h) a signal stops the reading: the outputs of the scans done so
// far are written (summary.json "interrupted": true) and the status is 130 /
// 143. Nothing is written when no scan was done. A run the divergence
// monitor flagged writes every output and returns kExitDiverged
// (divergence_cli.h) unless request.allow_divergence.
int RunOdometryOnBag(const RunRequest& request, RunOutcome* outcome);

struct RefineRequest {
  // bag, init_path (read when init is empty), out_dir, window, map, checkpoint and
  // chunk; the options come from config_files and overrides.
  RefineArgs args;
  std::vector<std::string> config_files;
  std::vector<std::string> overrides;  // --set key=value
  bool allow_divergence = false;       // exit 0 even if the checks of the result fired
  std::FILE* out = stdout;             // the round lines and the closing line
};

struct RefineOutcome {
  int scans = 0;
  double refine_s = 0.0;             // the batch solve (summary.json time_s.refine)
  double sequence_duration_s = 0.0;  // first to last refined pose
  bool diverged = false;             // the checks of the result fired (summary.json divergence)
};

// `rvlio refine` after its arguments are parsed (cmd_refine.cpp): loads the
// configuration and the initial trajectory, refines, writes the outputs and
// prints the command's lines (warnings and errors on stderr). Returns the exit
// status; the outcome is filled when the refinement finished.
int RefineOnBag(RefineRequest request, RefineOutcome* outcome);

}  // namespace rvlio::cli

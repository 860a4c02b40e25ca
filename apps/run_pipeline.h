#pragma once
// `rvlio run` as a function, so that demo and compare reuse it in-process:
// RunRecording (rvlio/api.h) with the command's signals, progress line and
// messages.
#include <string>
#include <utility>
#include <vector>

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

// Creates `dir` if needed and proves it writable; false after printing the
// error line of `command` if not (rvlio/outputs/output_stage.h PrepareOutputDir).
bool PrepareOutputDir(const std::string& command, const std::string& dir);

}  // namespace rvlio::cli

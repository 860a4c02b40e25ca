#pragma once
// `rvlio run` and `rvlio refine` after their arguments are parsed:
// RunRecording / RefineRecording (rvlio/api.h) with the command's signals,
// progress and round lines and messages; the lines compare prints as well.
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "cli.h"
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
};

// `rvlio refine` after its arguments are parsed (cmd_refine.cpp): loads the
// configuration and the initial trajectory, refines, writes the outputs and
// prints the command's lines (warnings and errors on stderr). Returns the exit
// status.
int RefineOnBag(RefineRequest request);

// The run's progress line on a terminal: scans, their rate, the share of the
// recording read.
class RunProgressLine {
 public:
  explicit RunProgressLine(bool enabled) : line_(enabled) {}
  void Update(const RunProgress& p);

 private:
  ProgressLine line_;
};

// refine's line after each round ("rvlio refine: round 2/3: cost ...").
void PrintRefineRound(std::FILE* out, const RefineRound& round, int rounds);
// refine's closing lines: a chunk job's span, "N scans, R rounds, solver,
// S s, peak memory -> DIR", and the control points' figures.
void PrintRefineDone(std::FILE* out, const RefineRunResult& result, double wall_s,
                     const std::string& out_dir);

}  // namespace rvlio::cli

#include "run_pipeline.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "cli.h"
#include "divergence_cli.h"
#include "interrupt.h"
#include "rvlio/api.h"
#include "rvlio/outputs/run_outputs.h"

namespace rvlio::cli {
namespace {

// A progress line on stderr for long runs, only when stderr is a terminal.
class Progress {
 public:
  explicit Progress(bool enabled) : enabled_(enabled && isatty(STDERR_FILENO)) {}
  void Update(const RunProgress& p) {
    if (!enabled_) return;
    const double wall = p.wall_s;
    if (wall < 3.0 || wall - last_print_ < 0.5) return;
    last_print_ = wall;
    const double done = p.fraction;
    const double eta = done > 0.01 ? wall * (1.0 - done) / done : 0.0;
    std::fprintf(stderr, "\r  scans %d  %.1f scans/s  %3.0f%%  ETA %.0f s   ", p.scans,
                 p.scans / wall, 100.0 * std::min(1.0, done), eta);
    printed_ = true;
  }
  ~Progress() {
    if (printed_) std::fprintf(stderr, "\n");
  }

 private:
  bool enabled_;
  double last_print_ = 0.0;
  bool printed_ = false;
};

// The one line of an interrupted run; returns its exit status (130 / 143).
int ReportInterrupt(const RunRequest& req, const RunResult& r) {
  if (r.scans.empty()) {
    std::fprintf(stderr, "rvlio run: interrupted by %s before the first scan was done; nothing "
                 "written\n", r.stop_reason.c_str());
  } else {
    std::fprintf(stderr, "rvlio run: interrupted by %s after %zu scans (up to t = %.3f s): wrote "
                 "trajectory.tum, map.pcd, scans.csv and summary.json to %s\n",
                 r.stop_reason.c_str(), r.scans.size(), NsToSeconds(r.scans.back().t_ns),
                 req.out_dir.c_str());
  }
  return InterruptExitCode();
}

}  // namespace

bool PrepareOutputDir(const std::string& command, const std::string& dir) {
  if (Status s = rvlio::PrepareOutputDir(dir); !s.ok()) {
    Fail(command, s.message());
    return false;
  }
  return true;
}

int RunOdometryOnBag(const RunRequest& req, RunOutcome* outcome) {
  std::vector<std::string> config_warnings;
  StatusOr<OdometryOptions> options =
      LoadConfig(req.config_files, req.overrides, &config_warnings);
  if (!options.ok()) return Fail("run", options.status().message());
  for (const auto& w : config_warnings) std::fprintf(stderr, "rvlio run: warning: %s\n", w.c_str());
  RunArgs args;
  args.bag = req.bag;
  args.options = *options;
  args.out_dir = req.out_dir;
  args.window = req.window;
  args.map = req.map;
  args.initial_pose = req.initial_pose;
  args.initial_pose_tum = req.initial_pose_tum;
  args.stop = [] { return InterruptSignalName(); };
  Progress progress(!req.quiet);
  size_t divergence_warned = 0;
  args.progress = [&progress, &divergence_warned](const RunProgress& p) {
    progress.Update(p);
    WarnDivergence("run", *p.divergence, &divergence_warned);
  };
  StatusOr<RunResult> result = RunRecording(args);
  if (!result.ok()) return Fail("run", result.status());
  if (result->scans.empty()) return ReportInterrupt(req, *result);  // stopped before a scan
  outcome->scans = static_cast<int>(result->scans.size());
  outcome->diverged = result->divergence.detected;
  outcome->median_ms = result->per_scan.median_ms;
  outcome->real_time_factor = result->real_time_factor;
  const Status& read_error = result->read_error;
  if (!read_error.ok())
    return Fail("run", read_error.message() + " (outputs hold the scans read before it)");
  for (const auto& w : result->warnings)
    std::fprintf(stderr, "rvlio run: warning: %s\n", w.c_str());
  if (result->stopped) return ReportInterrupt(req, *result);
  if (result->divergence.detected)
    return FinishDiverged("run", result->divergence, req.out_dir, req.allow_divergence,
                          !req.map.empty());
  return 0;
}

}  // namespace rvlio::cli

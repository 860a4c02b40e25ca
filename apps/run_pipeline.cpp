#include "run_pipeline.h"

#include <algorithm>
#include <cstdio>

#include "cli.h"
#include "divergence_cli.h"
#include "interrupt.h"
#include "rvlio/api.h"
#include "rvlio/outputs/run_outputs.h"

namespace rvlio::cli {
namespace {

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

void RunProgressLine::Update(const RunProgress& p) {
  if (!line_.Due(p.wall_s)) return;
  char what[64];
  std::snprintf(what, sizeof(what), "scans %d  %.1f scans/s", p.scans, p.scans / p.wall_s);
  line_.Update(p.wall_s, p.fraction, what);
}

void PrintRefineRound(std::FILE* out, const RefineRound& r, int rounds) {
  std::fprintf(out,
      "rvlio refine: round %d/%d: cost %.6g -> %.6g, %d iterations, max change %.4f m %.4f deg, "
      "%lld constraints, %d RV-active scans, %.1f s (deskew %.1f, map %.1f, associate %.1f, "
      "solve %.1f)\n",
      r.round, rounds, r.cost_before, r.cost_after, r.iterations, r.max_translation_change_m,
      r.max_rotation_change_deg, static_cast<long long>(r.constraints), r.rv_active_scans,
      r.total_s, r.deskew_s, r.map_s, r.associate_s, r.solve_s);
  std::fflush(out);
}

int RunOdometryOnBag(const RunRequest& req, RunOutcome* outcome) {
  std::vector<std::string> config_warnings;
  StatusOr<Configuration> options =
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
  RunProgressLine progress(!req.quiet);
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

// `rvlio refine`: RefineRecording (rvlio/api.h) with the command's arguments,
// signals and lines: reads the whole bag into memory (downsampled scans and
// all IMU samples; with --chunk K --of N only chunk K's scans and the IMU
// samples around them), batch-refines the initial trajectory
// (refine/refine.h) and writes trajectory.tum, map.pcd and summary.json
// (and chunk.json) atomically.
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <utility>

#include "cli.h"
#include "commands.h"
#include "common_options.h"
#include "divergence_cli.h"
#include "interrupt.h"
#include "run_pipeline.h"
#include "time_range_options.h"
#include "rvlio/common/cpu_time.h"
#include "rvlio/api.h"
#include "rvlio/api/refine_checkpoint.h"
#include "rvlio/formats/trajectory_io.h"

namespace rvlio::cli {
namespace {

using Clock = std::chrono::steady_clock;

// --checkpoint DIR / --resume DIR (the same folder goes on receiving checkpoints).
int ReadCheckpointArgs(const Args& args, RefineArgs* req) {
  if (args.Has("checkpoint") && args.Has("resume") &&
      args.Get("checkpoint") != args.Get("resume"))
    return Fail("refine", "--resume " + args.Get("resume") + " goes on checkpointing there; "
                "--checkpoint " + args.Get("checkpoint") + " names another folder");
  req->resume = args.Has("resume");
  req->checkpoint_dir = req->resume ? args.Get("resume") : args.Get("checkpoint");
  return 0;
}

// A whole number from an option's text; false for anything else.
bool ParseInt(const std::string& text, int* value) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno != 0 || v < INT_MIN || v > INT_MAX) return false;
  *value = static_cast<int>(v);
  return true;
}

// --chunk K --of N: both or neither, whole numbers (their range is checked
// against the initial trajectory by RefineRecording).
int ReadChunkArgs(const Args& args, RefineArgs* req) {
  if (args.Has("chunk") != args.Has("of"))
    return Fail("refine", args.Has("chunk") ? "--chunk needs --of N (the number of chunks)"
                                            : "--of needs --chunk K (which chunk, 1..N)");
  if (!args.Has("chunk")) return 0;
  if (!ParseInt(args.Get("chunk"), &req->chunk))
    return Fail("refine", "--chunk " + args.Get("chunk") + ": not a whole number");
  if (!ParseInt(args.Get("of"), &req->chunk_count))
    return Fail("refine", "--of " + args.Get("of") + ": not a whole number");
  if (req->chunk_count < 1)
    return Fail("refine", "--of " + args.Get("of") + ": needs at least 1 chunk");
  return 0;
}

}  // namespace

int CmdRefine(int argc, char** argv) {
  CommandSpec spec{"refine",
                   "Batch-refines a whole sequence starting from a previous run's trajectory "
                   "(all scans, IMU factors, re-association rounds; sparse Cholesky) and writes "
                   "trajectory.tum, map.pcd and summary.json to the output folder. SIGINT/SIGTERM "
                   "write the last completed round's result and exit 130/143.",
                   {{"bag", "PATH", "recording with LiDAR and IMU topics: ROS1 .bag, ROS 2 .db3, .mcap or bag folder; or Ouster packets (.pcap + metadata JSON, packet bag)", true},
                    {"init", "TUM", "initial trajectory (TUM format), e.g. rvlio run's", true},
                    ConfigOption(),
                    SetOption(),
                    OusterMetadataOption(),
                    {"out", "DIR", "output folder", true},
                    {"checkpoint", "DIR",
                     "after each round, write the state to continue from to DIR/refine.checkpoint"},
                    {"resume", "DIR",
                     "continue from DIR/refine.checkpoint (same --bag, --init, --map, --config and --set; "
                     "refine.rounds may differ) and go on checkpointing there"},
                    {"chunk", "K",
                     "refine only chunk K (1-based) of --of N overlapping chunks of the initial "
                     "trajectory's span (refine.job_overlap_s); writes chunk.json too, "
                     "for `rvlio merge`"},
                    {"of", "N", "the number of chunks (with --chunk)"},
                    {"map", "REF", "reference map (PCD or PLY, metres) in the --init trajectory's frame: every scan is also held to it (docs/survey.md)"},
                    {"control", "FILE", "control file (CSV: name,x,y,z[,role,sigma_m,t_start,t_end,map_x,map_y,map_z]): the trajectory is brought into the survey frame and tied to the control points; control.csv reports every row's residual (docs/control.md)"},
                    AllowDivergenceOption(),
                    StartOption(),
                    DurationOption()}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  InterruptScope interrupt_scope;
  RefineRequest req;
  if (std::string err = ParseWindow(args, &req.args.window); !err.empty())
    return Fail("refine", err);
  req.args.bag = args.Get("bag");
  req.args.init_path = args.Get("init");
  req.args.out_dir = args.Get("out");
  req.args.map = args.Get("map");
  req.args.control = args.Get("control");
  req.config_files = args.GetAll("config");
  req.overrides = OverridesOf(args);
  req.allow_divergence = args.Has("allow-divergence");
  if (int rc = ReadCheckpointArgs(args, &req.args); rc != 0) return rc;
  if (int rc = ReadChunkArgs(args, &req.args); rc != 0) return rc;
  return RefineOnBag(std::move(req));
}

namespace {

// "control points: 3, RMS 0.004 m; check points: 2, RMS 0.011 m, largest 0.015 m (M4)".
void PrintControl(std::FILE* out, const RefineRunResult& result) {
  std::string line;
  for (ControlRole role : {ControlRole::kControl, ControlRole::kCheck}) {
    const ControlRoleSummary r = SummarizeControlRole(result.control, role);
    if (r.count == 0) continue;
    char buf[256];
    std::snprintf(buf, sizeof(buf), "%s%s points: %d, RMS %.4f m, largest %.4f m (%s)",
                  line.empty() ? "" : "; ", ControlRoleName(role), r.count, r.rms_m, r.max_m,
                  r.max_name.c_str());
    line += buf;
  }
  if (result.gnss_fixes > 0) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "%sGNSS fixes: %d (%d outliers left out)",
                  line.empty() ? "" : "; ", result.gnss_fixes, result.gnss_outliers);
    line += buf;
  }
  if (!line.empty()) std::fprintf(out, "rvlio refine: %s\n", line.c_str());
}

}  // namespace

void PrintRefineDone(std::FILE* out, const RefineRunResult& result, double wall_s,
                     const std::string& out_dir) {
  const RefineResult& refined = result.refine;
  if (const std::optional<RefineJobSpan>& job = result.job)
    std::fprintf(out, "rvlio refine: chunk %d of %d: scans ending %.3f .. %.3f s (its own %.3f .. %.3f s)\n",
                 job->chunk, job->count, job->begin_ns * 1e-9, job->end_ns * 1e-9,
                 job->core_begin_ns * 1e-9, job->core_end_ns * 1e-9);
  std::fprintf(out, "rvlio refine: %zu scans, %zu rounds%s, %s, %.1f s, peak memory %.0f MB -> %s\n",
               refined.trajectory.size(), refined.rounds.size(),
               refined.converged ? " (converged)" : "", refined.linear_solver.c_str(), wall_s,
               PeakMemoryMb(), out_dir.c_str());
  PrintControl(out, result);
  std::fflush(out);
}

int RefineOnBag(RefineRequest request) {
  const auto t0 = Clock::now();
  RefineArgs& req = request.args;
  std::FILE* out = stdout;
  std::vector<std::string> config_warnings;
  StatusOr<Configuration> options =
      LoadConfig(request.config_files, request.overrides, &config_warnings);
  if (!options.ok()) return Fail("refine", options.status().message());
  for (const auto& w : config_warnings)
    std::fprintf(stderr, "rvlio refine: warning: %s\n", w.c_str());
  req.options = std::move(*options);
  if (req.init.empty()) {
    StatusOr<Trajectory> init = ReadTum(req.init_path);
    if (!init.ok()) return Fail("refine", "--init: " + init.status().message());
    req.init = std::move(*init);
  }
  const int rounds = req.options.refine.rounds;
  req.on_round = [out, rounds](const RefineRound& r) { PrintRefineRound(out, r, rounds); };
  req.on_resume = [out, &req](int rounds_done) {
    std::fprintf(out, "rvlio refine: resuming after round %d from %s\n", rounds_done,
                 req.checkpoint_dir.c_str());
  };
  req.stop = [] { return InterruptSignalName(); };
  StatusOr<RefineRunResult> result = RefineRecording(req);
  if (!result.ok()) return Fail("refine", result.status());
  if (!result->read_complete) {
    std::fprintf(stderr, "rvlio refine: interrupted by %s while reading the bag; nothing written\n",
                 result->stop_reason.c_str());
    return InterruptExitCode();
  }
  const RefineResult& refined = result->refine;
  for (const auto& w : refined.warnings) std::fprintf(stderr, "rvlio refine: warning: %s\n", w.c_str());
  size_t warned = 0;
  WarnDivergence("refine", result->divergence, &warned);
  if (result->stopped) {
    std::fprintf(stderr, "rvlio refine: interrupted by %s: wrote the result after round %zu "
                 "(trajectory.tum, map.pcd, summary.json) to %s\n", result->stop_reason.c_str(),
                 refined.rounds.empty() ? size_t{0} : static_cast<size_t>(refined.rounds.back().round),
                 req.out_dir.c_str());
    return InterruptExitCode();
  }
  PrintRefineDone(out, *result, SecondsSince(t0), req.out_dir);
  if (result->divergence.detected)
    return FinishDiverged("refine", result->divergence, req.out_dir, request.allow_divergence);
  return 0;
}

}  // namespace rvlio::cli

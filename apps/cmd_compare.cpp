// `rvlio compare` (and the comparison of `rvlio demo`): the flags into an
// experiments::CompareRequest, the library's RunCompare (rvlio/experiments/
// compare.h), then the command's lines, the plots and the tables.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cli.h"
#include "commands.h"
#include "common_options.h"
#include "divergence_cli.h"
#include "interrupt.h"
#include "plot_runner.h"
#include "run_pipeline.h"
#include "rvlio/common/cpu_time.h"
#include "rvlio/experiments/compare.h"
#include "rvlio/outputs/output_stage.h"
#include "time_range_options.h"

namespace rvlio::cli {
namespace {

namespace fs = std::filesystem;
namespace ex = experiments;
constexpr const char* kCompare = "compare";

std::string ResultLine(const ex::CompareRow& row) {
  if (row.interrupted) return row.name + " interrupted (its folder holds the scans it finished)";
  if (!row.measured())
    return row.name + " failed (exit " + std::to_string(row.exit_code) + ")" +
           (row.eval_error.empty() ? "" : ": " + row.eval_error);
  char buf[160];
  std::snprintf(buf, sizeof(buf), "ATE %.4f m, %d scans, %.1f s%s", row.eval->ape_m.rmse, row.scans,
                row.wall_s, row.diverged ? ", DIVERGED (summary.json divergence)" : "");
  std::string line = buf;
  if (row.map_eval) {
    std::snprintf(buf, sizeof(buf), "; map RMS %.4f m, completeness %.3f",
                  row.map_eval->accuracy.rmse, row.map_eval->completeness);
    line += buf;
  }
  return line;
}

// The command's lines while the comparison runs: "[k/n] ..." per step with
// its result below, the running variant's progress line and divergence
// warnings, and refine's rounds into OUT/refine/refine.log.
class StepPrinter {
 public:
  StepPrinter(const CompareOptions& o, const ex::CompareRequest& req) : o_(o), req_(req) {}

  void Step(const ex::CompareStep& s) {
    const ex::CompareRow& row = *s.row;
    const int total = o_.total_steps > 0 ? o_.total_steps : s.count;
    if (s.finished) {
      progress_.reset();
      if (log_ != nullptr) std::fclose(log_);
      log_ = nullptr;
      if (!o_.quiet) std::printf("      %s\n", ResultLine(row).c_str());
    } else if (row.name == ex::kRefineStep) {
      const std::string dir = req_.out_dir + "/" + row.name;
      Say(total, s.index, "rvlio refine from " + row.init + " (log: " + dir + "/refine.log)");
      std::error_code ec;
      fs::create_directories(dir, ec);  // for the log; refine itself reports a bad folder
      log_ = std::fopen((dir + "/refine.log").c_str(), "w");
      refine_t0_ = std::chrono::steady_clock::now();
    } else {
      Say(total, s.index, "rvlio run " + row.name + ": " + row.label);
      progress_ = std::make_unique<RunProgressLine>(!o_.quiet);
      divergence_warned_ = 0;
    }
    std::fflush(stdout);
  }
  void Run(const RunProgress& p) {
    if (progress_) progress_->Update(p);
    WarnDivergence("run", *p.divergence, &divergence_warned_);
  }
  void Round(const RefineRound& r, int rounds) {
    PrintRefineRound(log_ != nullptr ? log_ : stdout, r, rounds);
  }
  void RefineDone(const RefineRunResult& r) {
    size_t warned = 0;
    WarnDivergence("refine", r.divergence, &warned);
    PrintRefineDone(log_ != nullptr ? log_ : stdout, r, SecondsSince(refine_t0_),
                    req_.out_dir + "/" + ex::kRefineStep);
  }
  ~StepPrinter() {
    if (log_ != nullptr) std::fclose(log_);
  }

 private:
  void Say(int total, int index, const std::string& text) const {
    if (!o_.quiet) std::printf("[%d/%d] %s\n", o_.first_step + index, total, text.c_str());
  }
  const CompareOptions& o_;
  const ex::CompareRequest& req_;
  std::unique_ptr<RunProgressLine> progress_;
  size_t divergence_warned_ = 0;
  std::FILE* log_ = nullptr;
  std::chrono::steady_clock::time_point refine_t0_;
};

void PrintTable(const ex::CompareResult& result, bool with_map) {
  std::printf("\n  %-30s %9s %9s %12s %9s %9s %8s%s\n", "variant", "ATE [m]", "RPE [m]",
              "axis max [m]", "end [m]", "ms/scan", "speed",
              with_map ? "  map RMS [m]  complete" : "");
  for (const ex::CompareRow& r : result.rows) {
    if (r.interrupted || !r.measured()) {
      std::printf("  %-30s %s\n", r.label.c_str(),
                  r.interrupted ? "interrupted"
                                : ("failed (exit " + std::to_string(r.exit_code) + ")").c_str());
      continue;
    }
    std::string map_cols;
    if (with_map) {
      char buf[64];
      if (r.map_eval)
        std::snprintf(buf, sizeof(buf), "  %11.4f  %8.3f", r.map_eval->accuracy.rmse,
                      r.map_eval->completeness);
      else
        std::snprintf(buf, sizeof(buf), "  %11s  %8s", "-", "-");
      map_cols = buf;
    }
    std::printf("  %-30s %9.4f %9.4f %12.4f %9.4f %9.2f %7.1fx%s%s\n", r.label.c_str(),
                r.eval->ape_m.rmse, r.eval->rpe.trans_m.rmse, r.eval->along_axis.max_abs_m,
                r.eval->end_point_error_m, r.ms_per_scan, r.real_time_factor, map_cols.c_str(),
                r.diverged ? "  DIVERGED" : "");
  }
  std::printf(
      "\n  ATE: RMSE after %s alignment; RPE: 1-frame translation RMSE; axis max: largest\n"
      "  error along the tunnel axis; end: end-point error. ms/scan: median CPU time per\n"
      "  scan (refine: wall time of the batch solve per scan); speed: real-time factor.\n",
      ex::CompareAlignName(result).c_str());
  if (with_map)
    std::printf(
        "  map RMS: point-to-plane RMS of map.pcd (in the ground truth's frame by the ATE\n"
        "  alignment) to the reference cloud (points within 0.1 m); complete: reference\n"
        "  points with a map point within 0.1 m.\n");
}

const ex::CompareRow* FindOkRow(const ex::CompareResult& result, const std::string& name) {
  for (const ex::CompareRow& r : result.rows)
    if (r.name == name && r.ok()) return &r;
  return nullptr;
}

// Draws OUT/plots/{trajectories,rv_profile,compare_bars}.{png,pdf}.
ex::ComparePlots DrawPlots(const ex::CompareRequest& req, const ex::CompareResult& result) {
  ex::ComparePlots report;
  const std::string dir = req.out_dir + "/plots/";
  std::vector<std::pair<std::string, std::vector<std::string>>> jobs;
  std::vector<std::string> traj = {"trajectories", "--gt", req.gt, "--align", "se3", "--out", dir};
  for (const ex::CompareRow& r : result.rows)
    if (r.ok()) traj.insert(traj.end(), {"--run", r.name + "=" + req.out_dir + "/" + r.name});
  jobs.push_back({"trajectories", traj});
  if (FindOkRow(result, "ieskf_rv_on"))
    jobs.push_back(
        {"rv_profile",
         {"rv-profile", "--run", req.out_dir + "/ieskf_rv_on", "--gt", req.gt, "--out", dir}});
  std::vector<std::string> bars = {"compare-bars", "--table", req.out_dir + "/compare.csv", "--out",
                                   dir};
  if (!req.ref_map.empty())
    for (const char* metric :
         {"ate_rmse_m", "rpe_rmse_m", "axis_max_m", "map_rms_m", "map_completeness"})
      bars.insert(bars.end(), {"--metric", metric});
  jobs.push_back({"compare_bars", bars});
  std::vector<std::string> failures;
  for (const auto& [kind, args] : jobs) {
    const PlotResult p = RunPlotScript(args);
    if (!p.ran) {
      report.status = "skipped";
      report.message = p.message;
      return report;
    }
    if (!p.ok) {
      failures.push_back(kind + ": " + p.message);
      continue;
    }
    for (const char* ext : {".png", ".pdf"}) report.files.push_back(dir + kind + ext);
  }
  report.status = failures.empty() ? "ok" : "partial";
  for (const auto& f : failures) report.message += (report.message.empty() ? "" : "; ") + f;
  return report;
}

void PrintPlotReport(const ex::CompareRequest& req, const ex::ComparePlots& plots) {
  if (plots.status == "skipped") {
    std::printf("  plots skipped: %s\n", plots.message.c_str());
    return;
  }
  if (plots.status == "partial")
    std::fprintf(stderr, "rvlio %s: warning: some plots failed: %s\n", kCompare,
                 plots.message.c_str());
  if (plots.files.empty()) return;
  std::printf("  plots:  %s/plots/ (", req.out_dir.c_str());
  for (size_t i = 0; i < plots.files.size(); i += 2)
    std::printf("%s%s", i ? ", " : "", fs::path(plots.files[i]).stem().c_str());
  std::printf("; .png and .pdf)\n");
}

// compare.json without plots, and the one line; returns 130 / 143.
int ReportInterrupt(const ex::CompareRequest& req, const ex::CompareResult& result) {
  ex::ComparePlots plots;
  plots.status = "skipped";
  plots.message = "interrupted";
  if (Status s = ex::WriteCompareJson(req, result, plots); !s.ok())
    return Fail(kCompare, s.message(), 1);
  int finished = 0;
  for (const ex::CompareRow& r : result.rows) finished += r.interrupted ? 0 : 1;
  std::fprintf(stderr,
               "rvlio compare: interrupted by %s: %d of %zu steps finished; wrote "
               "compare.{csv,md,json} (the rest marked interrupted) to %s\n",
               InterruptSignalName().c_str(), finished, result.rows.size(), req.out_dir.c_str());
  return InterruptExitCode();
}

// After the runs: the tables, the terminal table, the plots and the exit status.
int Finish(const ex::CompareRequest& req, const CompareOptions& o,
           const ex::CompareResult& result) {
  if (Status s = ex::WriteCompareTables(req, result); !s.ok())
    return Fail(kCompare, s.message(), 1);
  PrintTable(result, !req.ref_map.empty());
  if (Interrupted()) return ReportInterrupt(req, result);
  const bool any_ok = result.Best() != nullptr;
  ex::ComparePlots plots;
  if (o.plots && any_ok) plots = DrawPlots(req, result);
  if (Status s = ex::WriteCompareJson(req, result, plots); !s.ok())
    return Fail(kCompare, s.message(), 1);
  std::printf("\n  tables: %s/compare.{csv,md,json}; runs: %s/<variant>/\n", req.out_dir.c_str(),
              req.out_dir.c_str());
  if (o.plots) PrintPlotReport(req, plots);
  WriteFolderReport(kCompare, req.out_dir, o.quiet);
  const int diverged = result.Diverged();
  if (!any_ok && diverged > 0)
    return Fail(kCompare,
                "every variant failed or diverged (see the table and each run's "
                "summary.json divergence)",
                kExitDiverged);
  if (!any_ok) return Fail(kCompare, "every variant failed (see the table)", 1);
  if (diverged > 0)
    std::fprintf(stderr, "rvlio %s: warning: %d run(s) diverged, marked in the table\n", kCompare,
                 diverged);
  return 0;
}

}  // namespace

int CompareOnDisk(experiments::CompareRequest req, const CompareOptions& o) {
  InterruptScope interrupt_scope;  // SIGINT/SIGTERM: stop the running variant, tabulate, 130/143
  OutputFolder out_folder(req.out_dir);  // removed again when it stays empty (bad input)
  if (Status s = out_folder.Prepare(); !s.ok()) return Fail(kCompare, s);
  StepPrinter printer(o, req);
  req.stop = [] { return InterruptSignalName(); };
  req.stop_exit_code = [] { return InterruptExitCode(); };
  req.on_step = [&printer](const ex::CompareStep& s) { printer.Step(s); };
  req.on_run_progress = [&printer](const RunProgress& p) { printer.Run(p); };
  req.on_refine_round = [&printer](const RefineRound& r, int rounds) { printer.Round(r, rounds); };
  req.on_refine_result = [&printer](const RefineRunResult& r) { printer.RefineDone(r); };
  req.on_warning = [](const std::string& w) {
    std::fprintf(stderr, "rvlio %s: warning: %s\n", kCompare, w.c_str());
  };
  StatusOr<ex::CompareResult> result = ex::RunCompare(req);
  if (!result.ok()) return Fail(kCompare, result.status());
  return Finish(req, o, *result);
}

int CmdCompare(int argc, char** argv) {
  CommandSpec spec{
      "compare",
      "Runs the standard variants on one sequence - IESKF and smoother, each with the RV modules\n"
      "off and on - then `refine` from the best of them by ATE; evaluates each against the\n"
      "ground truth (se3 alignment) and writes OUT/<variant>/ (run outputs), OUT/compare.csv,\n"
      "compare.md, compare.json and OUT/plots/ (trajectories, RV profile, bar chart; needs\n"
      "python3 with matplotlib). Exit 0 when at least one variant ran, 1 when all failed,\n"
      "2 on bad input (before any run).",
      {{"bag", "PATH",
        "recording with LiDAR and IMU topics: ROS1 .bag, ROS 2 .db3, .mcap or bag folder", true},
       {"gt", "TUM", "ground-truth trajectory (TUM or KITTI, as rvlio eval)", true},
       {"ref-map", "FILE",
        "reference cloud (PCD/PLY, the ground truth's frame): adds map accuracy "
        "and completeness columns (as rvlio eval --map)"},
       ConfigOption(),
       SetOption(),
       {"out", "DIR", "output folder", true},
       StartOption(),
       DurationOption(),
       {"no-refine", "", "skip the refine step"},
       {"no-plots", "", "do not draw plots"},
       {"quiet", "", "no step lines or progress; the table is still printed"}}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  experiments::CompareRequest req;
  req.bag = args.Get("bag");
  req.gt = args.Get("gt");
  req.ref_map = args.Get("ref-map");
  req.out_dir = args.Get("out");
  req.config_files = args.GetAll("config");
  req.overrides = args.GetAll("set");
  req.refine = !args.Has("no-refine");
  CompareOptions o;
  o.plots = !args.Has("no-plots");
  o.quiet = args.Has("quiet");
  if (std::string err = ParseWindow(args, &req.window); !err.empty()) return Fail(kCompare, err);
  return CompareOnDisk(std::move(req), o);
}

}  // namespace rvlio::cli

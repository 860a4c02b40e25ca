// rvlio ablate: a grid of sequences x variants x parameters, one `rvlio run`
// process per cell, resumable, with a summary over seeds. The grid format is
// described in ablate_grid.h and workflow/README.md; --plan, --data, --cell
// and --summarize are the machine interface of workflow/Snakefile.
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "ablate_runner.h"
#include "commands.h"
#include "common_options.h"
#include "interrupt.h"
#include "plot_runner.h"
#include "rvlio/experiments/ablate_grid.h"
#include "rvlio/experiments/ablate_summary.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/outputs/output_stage.h"
#include "rvlio/outputs/summary_json.h"

namespace rvlio::cli {
namespace {

constexpr const char* kAblate = "ablate";
constexpr int kMaxJobs = 256;

CommandSpec AblateSpec() {
  return {kAblate,
          "Runs a grid of sequences x variants x parameters: each cell is one `rvlio run`\n"
          "process, evaluated against ground truth, recorded in OUT/cells/<id>/cell.json.\n"
          "Resumable: finished cells (same configuration hash) are skipped. Writes\n"
          "OUT/summary.csv (one row per cell), OUT/table.csv and OUT/table.md (mean and std\n"
          "over seeds) and plots. A failing cell is recorded, not fatal (exit status 0).",
          {{"grid", "FILE", "grid description (YAML, see workflow/README.md)", true},
           {"out", "DIR", "output folder", true},
           {"jobs", "N", "cells run in parallel (default 1)"},
           {"max-cells", "N",
            "largest grid accepted (default " +
                std::to_string(experiments::ablate::kDefaultMaxCells) +
                " cells)"},
           {"plan", "", "print the expanded cells as JSON and exit (runs nothing)"},
           {"summarize", "", "only build the summary from the finished cells"},
           {"cell", "ID", "run only this cell of the plan (Snakemake jobs)"},
           {"data", "ID", "only simulate this sequence/seed of the plan"},
           {"no-plots", "", "do not call the plot script"},
           {"quiet", "", "no progress output"}}};
}

std::string SelfPath() {
  std::error_code ec;
  const auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("rvlio") : p.string();
}

// Returns 0 and sets `max_cells`, or the exit status after an error.
int ReadMaxCells(const Args& args, int64_t* max_cells) {
  *max_cells = experiments::ablate::kDefaultMaxCells;
  if (!args.Has("max-cells")) return 0;
  const std::string text = args.Get("max-cells");
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno != 0 || v < 1)
    return Fail(kAblate, "--max-cells '" + text + "' is not a positive whole number");
  *max_cells = v;
  return 0;
}

// Returns 0 and sets `jobs`, or the exit status after an error.
int ReadJobs(const Args& args, int* jobs) {
  *jobs = 1;
  if (!args.Has("jobs")) return 0;
  const std::string text = args.Get("jobs");
  long long v = 0;
  if (!ParseWholeNumber(text, 1, kMaxJobs, &v))
    return Fail(kAblate, "--jobs '" + text + "' is not a whole number in [1, " +
                           std::to_string(kMaxJobs) + "]");
  *jobs = static_cast<int>(v);
  return 0;
}

// The summary's bar chart: "plots: ..." or why there is none.
std::string DrawSummaryPlot(const ablate::Plan& plan, const experiments::ablate::SummaryResult& r) {
  if (r.done == 0) return "plots skipped: no finished cell";
  std::string prefix;
  const PlotResult p = RunPlotScript(experiments::ablate::SummaryPlotArgs(plan, &prefix));
  if (!p.ran) return "plots skipped: " + p.message;
  if (!p.ok) return "plots failed: " + p.message;
  return "plots: " + prefix + "_ablation.png, " + prefix + "_ablation.pdf";
}

int Summarize(const ablate::Plan& plan, const Args& args) {
  StatusOr<experiments::ablate::SummaryResult> r = experiments::ablate::WriteSummary(plan);
  if (!r.ok()) return Fail(kAblate, r.status());
  const std::string plot_note =
      args.Has("no-plots") ? "plots skipped: --no-plots" : DrawSummaryPlot(plan, *r);
  std::cout << r->table_md;
  std::printf("rvlio ablate: %d cells: %d done, %d failed, %d not run -> %s/table.md\n", r->cells,
              r->done, r->failed, r->missing, plan.out_dir.c_str());
  if (r->diverged > 0)
    std::printf("rvlio ablate: %d cells diverged (status diverged in summary.csv; left out of the "
                "means)\n", r->diverged);
  std::printf("rvlio ablate: %s\n", plot_note.c_str());
  WriteFolderReport(kAblate, plan.out_dir, false);
  return 0;
}

// The one line after a signal; returns 130 / 143.
int ReportInterrupt(const ablate::RunCounts& c) {
  std::fprintf(stderr,
               "rvlio ablate: interrupted by %s: %d cells finished now and kept (%d were done "
               "before), %d stopped and %d not started (run next time)\n",
               InterruptSignalName().c_str(), c.done + c.failed, c.skipped, c.interrupted,
               c.not_started);
  return InterruptExitCode();
}

int RunSingle(const ablate::Plan& plan, const std::string& id, const ablate::RunnerOptions& o) {
  ablate::RunCounts counts;
  if (!ablate::RunOne(plan, id, o, &counts))
    return Fail(kAblate,
                "no cell or data '" + id + "' in the plan of " + plan.grid_path + " (see --plan)");
  if (Interrupted()) return ReportInterrupt(counts);
  const char* what = counts.skipped ? "already done" : counts.failed ? "failed (recorded)" : "done";
  std::printf("rvlio ablate: %s %s\n", id.c_str(), what);
  return 0;
}

}  // namespace

int CmdAblate(int argc, char** argv) {
  const CommandSpec spec = AblateSpec();
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  ablate::RunnerOptions options;
  if (int rc = ReadJobs(args, &options.jobs); rc != 0) return rc;
  int modes = 0;
  for (const char* m : {"plan", "summarize", "cell", "data"}) modes += args.Has(m) ? 1 : 0;
  if (modes > 1) return Fail(kAblate, "--plan, --summarize, --cell and --data exclude each other");
  options.rvlio_bin = SelfPath();
  options.progress = !args.Has("quiet");

  int64_t max_cells = 0;
  if (int rc = ReadMaxCells(args, &max_cells); rc != 0) return rc;
  StatusOr<ablate::Plan> plan =
      experiments::ablate::LoadPlan(args.Get("grid"), args.Get("out"), max_cells);
  if (!plan.ok()) return Fail(kAblate, plan.status());
  if (args.Has("plan")) {
    std::cout << experiments::ablate::PlanJsonText(*plan);
    return 0;
  }
  OutputFolder out_folder(plan->out_dir);  // removed again when it stays empty
  if (Status s = out_folder.Prepare(); !s.ok()) return Fail(kAblate, s);
  if (args.Has("summarize")) return Summarize(*plan, args);
  InterruptScope interrupt_scope;  // SIGINT/SIGTERM: finished cells stay, the rest run next time
  if (args.Has("cell")) return RunSingle(*plan, args.Get("cell"), options);
  if (args.Has("data")) return RunSingle(*plan, args.Get("data"), options);

  const std::string plan_json = experiments::ablate::PlanJsonText(*plan);
  if (Status s = WriteFileAtomically(plan->out_dir + "/plan.json", plan_json); !s.ok())
    return Fail(kAblate, s);
  if (options.progress)
    std::printf("rvlio ablate: the grid has %zu cells (%zu simulated sequences) -> %s\n",
                plan->cells.size(), plan->data.size(), plan->out_dir.c_str());
  const ablate::RunCounts c = ablate::RunPlan(*plan, options);
  if (Interrupted()) return ReportInterrupt(c);
  std::printf("rvlio ablate: %d cells: %d already done, %d run now (%d done, %d failed)\n", c.total,
              c.skipped, c.done + c.failed, c.done, c.failed);
  return Summarize(*plan, args);
}

}  // namespace rvlio::cli

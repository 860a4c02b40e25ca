// rvlio ablate: a grid of sequences x variants x parameters, one `rvlio run`
// process per cell, resumable, with a summary over seeds. The grid format is
// described in rvlio/experiments/ablate_grid.h and workflow/README.md; --plan,
// --data, --cell and --summarize are the machine interface of
// workflow/Snakefile. The plan, the runner, the cells' records and the
// summary are the library's (rvlio/experiments/ablate_*.h).
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>

#include "commands.h"
#include "common_options.h"
#include "interrupt.h"
#include "plot_runner.h"
#include "divergence_cli.h"
#include "rvlio/experiments/ablate_grid.h"
#include "rvlio/experiments/ablate_runner.h"
#include "rvlio/experiments/ablate_summary.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/outputs/output_stage.h"
#include "rvlio/outputs/summary_json.h"

namespace rvlio::cli {
namespace {

namespace ablate = experiments::ablate;

constexpr const char* kAblate = "ablate";
constexpr int kMaxJobs = 256;

// "[12/40] done 11, failed 1, running 2": rewritten in place on a terminal,
// one plain line per finished item otherwise.
class Progress {
 public:
  Progress(bool enabled, const std::string& what, int total, int skipped)
      : tty_(enabled && isatty(STDERR_FILENO)),
        enabled_(enabled),
        what_(what),
        total_(total),
        skipped_(skipped) {}
  void Running(int n) {
    running_ = n;
    if (tty_) Draw();
  }
  void Stopped(const std::string& name) {
    ++stopped_;
    if (!tty_ && enabled_) std::fprintf(stderr, "%s %s interrupted\n", what_.c_str(), name.c_str());
  }
  void Finished(const std::string& name, bool ok, double wall_s) {
    (ok ? done_ : failed_)++;
    if (tty_)
      Draw();
    else if (enabled_)
      std::fprintf(stderr, "[%d/%d] %s %s %s (%.1f s)\n", skipped_ + done_ + failed_, total_,
                   what_.c_str(), name.c_str(), ok ? "done" : "FAILED", wall_s);
  }
  ~Progress() {
    if (drawn_) std::fprintf(stderr, "\n");
  }

 private:
  void Draw() {
    std::fprintf(stderr, "\r[%d/%d] %s: done %d, failed %d, running %d   ",
                 skipped_ + done_ + failed_, total_, what_.c_str(), skipped_ + done_, failed_,
                 running_);
    drawn_ = true;
  }
  bool tty_, enabled_;
  std::string what_;
  int total_, skipped_, done_ = 0, failed_ = 0, running_ = 0, stopped_ = 0;
  bool drawn_ = false;
};

// The runner's children receive this process's signals (interrupt.h), and its
// batches are shown by a Progress line.
class CliHooks : public ablate::RunnerHooks {
 public:
  explicit CliHooks(bool progress) : progress_(progress) {}
  bool Stopped() override { return Interrupted(); }
  bool ChildStarted(pid_t pid) override { return AddForwardPid(pid); }
  void ChildEnded(pid_t pid) override { RemoveForwardPid(pid); }
  void BatchStarted(const std::string& what, int total, int skipped) override {
    batch_ = std::make_unique<Progress>(progress_, what, total, skipped);
  }
  void Running(int n) override { batch_->Running(n); }
  void Finished(const std::string& item, bool ok, double wall_s) override {
    batch_->Finished(item, ok, wall_s);
  }
  void StoppedItem(const std::string& item) override { batch_->Stopped(item); }
  void BatchEnded() override { batch_.reset(); }
  void RecordError(const Status& error) override {
    std::fprintf(stderr, "rvlio ablate: error: %s\n", error.message().c_str());
  }

 private:
  bool progress_;
  std::unique_ptr<Progress> batch_;
};

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
                std::to_string(ablate::kDefaultMaxCells) +
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
  *max_cells = ablate::kDefaultMaxCells;
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
std::string DrawSummaryPlot(const ablate::Plan& plan, const ablate::SummaryResult& r) {
  if (r.done == 0) return "plots skipped: no finished cell";
  std::string prefix;
  const PlotResult p = RunPlotScript(ablate::SummaryPlotArgs(plan, &prefix));
  if (!p.ran) return "plots skipped: " + p.message;
  if (!p.ok) return "plots failed: " + p.message;
  return "plots: " + prefix + "_ablation.png, " + prefix + "_ablation.pdf";
}

int Summarize(const ablate::Plan& plan, const Args& args) {
  StatusOr<ablate::SummaryResult> r = ablate::WriteSummary(plan);
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

int RunSingle(const ablate::Plan& plan, const std::string& id, const ablate::RunnerOptions& o,
              CliHooks* hooks) {
  ablate::RunCounts counts;
  if (!ablate::RunOne(plan, id, o, hooks, &counts))
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
  options.diverged_exit_code = kExitDiverged;
  CliHooks hooks(!args.Has("quiet"));

  int64_t max_cells = 0;
  if (int rc = ReadMaxCells(args, &max_cells); rc != 0) return rc;
  StatusOr<ablate::Plan> plan =
      ablate::LoadPlan(args.Get("grid"), args.Get("out"), max_cells);
  if (!plan.ok()) return Fail(kAblate, plan.status());
  if (args.Has("plan")) {
    std::cout << ablate::PlanJsonText(*plan);
    return 0;
  }
  OutputFolder out_folder(plan->out_dir);  // removed again when it stays empty
  if (Status s = out_folder.Prepare(); !s.ok()) return Fail(kAblate, s);
  if (args.Has("summarize")) return Summarize(*plan, args);
  InterruptScope interrupt_scope;  // SIGINT/SIGTERM: finished cells stay, the rest run next time
  if (args.Has("cell")) return RunSingle(*plan, args.Get("cell"), options, &hooks);
  if (args.Has("data")) return RunSingle(*plan, args.Get("data"), options, &hooks);

  const std::string plan_json = ablate::PlanJsonText(*plan);
  if (Status s = WriteFileAtomically(plan->out_dir + "/plan.json", plan_json); !s.ok())
    return Fail(kAblate, s);
  if (!args.Has("quiet"))
    std::printf("rvlio ablate: the grid has %zu cells (%zu simulated sequences) -> %s\n",
                plan->cells.size(), plan->data.size(), plan->out_dir.c_str());
  const ablate::RunCounts c = ablate::RunPlan(*plan, options, &hooks);
  if (Interrupted()) return ReportInterrupt(c);
  std::printf("rvlio ablate: %d cells: %d already done, %d run now (%d done, %d failed)\n", c.total,
              c.skipped, c.done + c.failed, c.done, c.failed);
  return Summarize(*plan, args);
}

}  // namespace rvlio::cli

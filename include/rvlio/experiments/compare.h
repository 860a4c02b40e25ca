#pragma once
// `rvlio compare` as a library call (target rvlio::experiments): the standard
// variants on one recording (IESKF and smoother, RV off and on), then refine
// from the best of them, each evaluated against the ground truth in memory.
// Every run writes its usual folder OUT/<variant>/ (rvlio/api.h); the figures
// and the trajectories come back typed in CompareResult, and the tables
// (compare.csv, .md, .json) are written from them by WriteCompareTables.
// Nothing is printed: progress, warnings and refine's rounds reach the
// caller through the callbacks of CompareRequest.
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "rvlio/api.h"
#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/eval/evaluate.h"
#include "rvlio/eval/map_metrics.h"
#include "rvlio/formats/sensor_stream.h"

namespace rvlio::experiments {

// One standard variant: its folder name, its label and its `--set` overrides
// (applied after the request's own).
struct CompareVariant {
  std::string name, label;
  std::vector<std::string> overrides;
};
const std::vector<CompareVariant>& StandardVariants();

// The name of the refine step (its folder OUT/refine/ and its row).
inline constexpr const char* kRefineStep = "refine";

struct CompareRow;

// What the progress callback receives: once when a step (a variant's run or
// refine) starts, with the row's name, label and init only, and once when it
// has finished, with the whole row.
struct CompareStep {
  int index = 0;  // 0-based, in the order of the rows
  int count = 0;  // the steps of the request (CompareSteps)
  bool finished = false;
  const CompareRow* row = nullptr;
};

struct CompareRequest {
  std::string bag;
  std::string gt;       // ground-truth trajectory (TUM or KITTI, as `rvlio eval`)
  std::string ref_map;  // reference cloud (PCD/PLY): map metrics when set (docs/map_eval.md)
  std::string out_dir;  // OUT/<variant>/ for each run, and the tables
  std::vector<std::string> config_files;
  std::vector<std::string> overrides;  // key=value, before each variant's own
  bool refine = true;
  ReadWindow window;  // part of the recording, for every variant and refine
  StopFn stop;        // polled by each run; a stop marks that step and the rest interrupted
  // The exit status written in the tables' exit_code column for an
  // interrupted step (the command: 130 for SIGINT, 143 for SIGTERM).
  std::function<int()> stop_exit_code;
  std::function<void(const CompareStep&)> on_step;
  std::function<void(const std::string&)> on_warning;  // "<step>: <what>"
  // The running variant's progress (RunArgs::progress), and refine's rounds
  // with the number of rounds configured (refine.rounds).
  std::function<void(const RunProgress&)> on_run_progress;
  std::function<void(const RefineRound&, int rounds)> on_refine_round;
  // refine's whole result when it finished (not after a stop), before it is
  // evaluated (e.g. for its closing lines).
  std::function<void(const RefineRunResult&)> on_refine_result;
};

// The steps (runs) a request makes: 4 variants, + refine.
int CompareSteps(const CompareRequest& request);

// One step's outcome, typed: what compare.csv and compare.json tabulate.
struct CompareRow {
  static constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();
  std::string name, label;
  std::vector<std::string> overrides;  // the variant's own (none for refine)
  std::string init;                    // refine: the variant it started from
  // 0 ran; 1 or 2 failed (ExitStatus of run_error); an interrupted step:
  // CompareRequest::stop_exit_code().
  int exit_code = 0;
  Status run_error;        // why the run failed (exit_code != 0)
  std::string eval_error;  // "evaluation: ..." when the run ended but could not be evaluated
  std::optional<EvalResult> eval;
  std::optional<MapEvalResult> map_eval;  // with ref_map: the step's map (as map.pcd stores it) against it
  // The estimate as trajectory.tum holds it (RoundTripTum): what was evaluated.
  Trajectory trajectory;
  int scans = 0;
  double ms_per_scan = kUnknown;       // run: median CPU ms; refine: wall ms per scan
  double real_time_factor = kUnknown;  // sequence duration / compute time
  double wall_s = 0.0;                 // the whole step, reading included
  bool interrupted = false;            // a stop ended it or came before it started
  bool diverged = false;               // the divergence monitor fired: figures shown, marked

  bool measured() const { return exit_code == 0 && eval.has_value(); }
  bool ok() const { return measured() && !diverged; }
  const char* StatusName() const;  // "interrupted", "ok", "diverged" or "failed"
};

struct CompareResult {
  std::vector<CompareRow> rows;    // the variants in order, then refine when it ran
  bool interrupted = false;        // the stop came: later steps are marked interrupted
  const CompareRow* Best() const;  // the smallest ATE among the ok rows (nullptr: none)
  int Diverged() const;
};

// Checks every input (configuration of every variant, ground truth, reference
// cloud, the recording's topics) before any run: InvalidInput, one line, and
// nothing written. Then runs the steps; a failing step is a row, not an error.
// The configuration is loaded once; trajectories stay in memory.
StatusOr<CompareResult> RunCompare(const CompareRequest& request);

// The exit status of the command-line contract for a library error: 2 for
// bad input or an output that cannot be written, 1 for an internal failure.
int ExitStatus(StatusCode code);

// The plots drawn after the runs (by the caller), recorded in compare.json.
struct ComparePlots {
  std::string status = "not requested";  // "ok", "skipped", "partial"
  std::string message;
  std::vector<std::string> files;
};

// The alignment the evaluation used (the first measured row's; "se3" when none).
std::string CompareAlignName(const CompareResult& result);
std::string CompareCsv(const CompareRequest& request, const CompareResult& result);
std::string CompareMarkdown(const CompareRequest& request, const CompareResult& result);
std::string CompareJsonText(const CompareRequest& request, const CompareResult& result,
                            const ComparePlots& plots);
// OUT/compare.csv and compare.md (atomically).
Status WriteCompareTables(const CompareRequest& request, const CompareResult& result);
// OUT/compare.json (atomically).
Status WriteCompareJson(const CompareRequest& request, const CompareResult& result,
                        const ComparePlots& plots);

}  // namespace rvlio::experiments

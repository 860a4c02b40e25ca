#pragma once
// Runs the cells of an ablation plan (rvlio/experiments/ablate_grid.h): each
// simulated sequence once per seed (`rvlio simulate`) and each cell as its
// own `rvlio run` process (spawned directly, no shell), then records the
// cell (rvlio/experiments/ablate_cells.h: evaluated in-process) in
// CELL/cell.json atomically. A crashing or failing run is recorded in its
// cell.json ("status": "failed"), never fatal for the others. Finished cells
// (status done, same hash) and finished data (data.json, same hash) are skipped.
// SIGINT/SIGTERM (under an InterruptScope, interrupt.h) reach the running
// children, which run in their own process group; no further child starts,
// the children the signal stopped leave no cell.json and no run folder.
#include <string>

#include "rvlio/experiments/ablate_grid.h"

namespace rvlio::cli::ablate {

using experiments::ablate::Cell;
using experiments::ablate::DataItem;
using experiments::ablate::Plan;

struct RunCounts {
  int total = 0;
  int skipped = 0;  // already done before this call
  int done = 0;     // finished now (including cells whose run diverged: cell.json says so)
  int failed = 0;   // failed now (including cells whose data failed)
  int interrupted = 0;  // stopped by a signal: nothing kept, run again next time
  int not_started = 0;  // not started because of a signal
};

struct RunnerOptions {
  std::string rvlio_bin;  // the program spawned for simulate/run
  int jobs = 1;
  bool progress = true;  // "\r[12/40] ..." on a terminal stderr, plain lines otherwise
};

// Everything the plan needs: data first, then cells, `jobs` at a time.
RunCounts RunPlan(const Plan& plan, const RunnerOptions& options);

// Only one data item or one cell (the Snakemake jobs). A cell prepares its
// data first if that is missing. Returns false when `id` is not in the plan.
bool RunOne(const Plan& plan, const std::string& id, const RunnerOptions& options,
            RunCounts* counts);

}  // namespace rvlio::cli::ablate

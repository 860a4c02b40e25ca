#pragma once
// Runs the cells of an ablation plan: each simulated sequence once per seed
// (`rvlio simulate`) and each cell as its own `rvlio run` process (spawned
// directly, no shell), then evaluates the trajectory in-process and writes
// CELL/cell.json atomically. A crashing or failing run is recorded in its
// cell.json ("status": "failed"), never fatal for the others. Finished cells
// (status done, same hash) and finished data (data.json, same hash) are skipped.
// SIGINT/SIGTERM (under an InterruptScope, interrupt.h) reach the running
// children, which run in their own process group; no further child starts,
// the children the signal stopped leave no cell.json and no run folder.
#include <string>

#include <nlohmann/json.hpp>

#include "ablate_grid.h"

namespace rvlio::cli::ablate {

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

// cell.json of a finished cell with the plan's hash (status done, diverged
// (the run's divergence monitor fired: exit 3, metrics kept) or failed), or
// null when there is none.
nlohmann::json ReadCellRecord(const Cell& cell);

// Which optional metric groups a grid's tables carry.
struct MetricSet {
  bool map = false;        // map_rms, map_completeness: some cell has a ref_map
  bool detection = false;  // detect_precision, detect_recall: some sequence is simulated
};
MetricSet MetricSetOf(const Plan& plan);

// The metric fields of cell.json "metrics" (name) and the Markdown table's
// header of each, in table order.
struct MetricColumn {
  std::string name, header;
};
const std::vector<MetricColumn>& MetricColumns(MetricSet set = MetricSet());

}  // namespace rvlio::cli::ablate

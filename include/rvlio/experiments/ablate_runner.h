#pragma once
// Runs the cells of an ablation plan (ablate_grid.h, target rvlio::experiments):
// each simulated sequence once per seed (`rvlio simulate`) and each cell as
// its own `rvlio run` process (spawned directly, no shell, in its own process
// group), then records the cell (ablate_cells.h: evaluated in-process) in
// CELL/cell.json atomically. A crashing or failing run is recorded in its
// cell.json ("status": "failed"), never fatal for the others. Finished cells
// (status done, same hash) and finished data (data.json, same hash) are
// skipped. After a stop (RunnerHooks::Stopped) no further child starts; the
// children a forwarded signal stopped leave no cell.json and no run folder.
#include <sys/types.h>

#include <string>

#include "rvlio/common/status.h"
#include "rvlio/experiments/ablate_grid.h"

namespace rvlio::experiments::ablate {

struct RunCounts {
  int total = 0;
  int skipped = 0;      // already done before this call
  int done = 0;         // finished now (including cells whose run diverged: cell.json says so)
  int failed = 0;       // failed now (including cells whose data failed)
  int interrupted = 0;  // stopped by a signal: nothing kept, run again next time
  int not_started = 0;  // not started because of a stop
};

struct RunnerOptions {
  std::string rvlio_bin;  // the program spawned for simulate/run
  int jobs = 1;
  int diverged_exit_code = 3;  // `rvlio run`'s status for a run whose divergence monitor fired
};

// What the caller sees of the runner: its stop, the children (to forward
// signals to them) and the progress. The defaults do nothing.
class RunnerHooks {
 public:
  virtual ~RunnerHooks() = default;
  // Polled between children: true starts no more (and marks children that
  // ended by SIGINT / SIGTERM as stopped). Called with SIGINT and SIGTERM
  // blocked while children are started.
  virtual bool Stopped() { return false; }
  // A child was started; false: it cannot be followed (it is killed and its
  // item recorded as not started).
  virtual bool ChildStarted(pid_t /*pid*/) { return true; }
  virtual void ChildEnded(pid_t /*pid*/) {}
  // One batch (the data, then the cells): its items, those done before.
  virtual void BatchStarted(const std::string& /*what*/, int /*total*/, int /*skipped*/) {}
  virtual void Running(int /*children*/) {}
  virtual void Finished(const std::string& /*item*/, bool /*ok*/, double /*wall_s*/) {}
  virtual void StoppedItem(const std::string& /*item*/) {}
  virtual void BatchEnded() {}
  // cell.json could not be written (the cell runs again next time).
  virtual void RecordError(const Status& /*error*/) {}
};

// Everything the plan needs: data first, then cells, `jobs` at a time.
RunCounts RunPlan(const Plan& plan, const RunnerOptions& options, RunnerHooks* hooks = nullptr);

// Only one data item or one cell (the Snakemake jobs). A cell prepares its
// data first if that is missing. Returns false when `id` is not in the plan.
bool RunOne(const Plan& plan, const std::string& id, const RunnerOptions& options,
            RunnerHooks* hooks, RunCounts* counts);

}  // namespace rvlio::experiments::ablate

#pragma once
// The record of one ablation cell (CELL/cell.json, target rvlio::experiments):
// the run's figures from its summary.json, its trajectory against the ground
// truth (rvlio/eval/evaluate.h), its map against the reference cloud and,
// on simulated data, its degeneracy detection against the simulator's truth.
// The runner (ablate_runner.h) starts each cell's `rvlio run` and records it
// here; the summary and the report read only these records.
#include <optional>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/experiments/ablate_grid.h"

namespace rvlio::experiments::ablate {

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

// How a cell's run ended, as its runner saw it.
struct CellRunEnd {
  std::optional<int> exit_code;  // none: it did not exit (a signal, or never started)
  std::string how;               // "exited with status 2", "killed by signal 11 (...)", ...
  bool diverged = false;         // it ran to the end but its divergence monitor fired
  double wall_s = 0.0;
  std::string log_tail;  // the last lines of its output
};

// A cell's state, as its cell.json records it.
enum class CellStatus {
  kMissing,   // no cell.json with the plan's hash: not run (or stopped)
  kDone,      // finished, evaluated
  kDiverged,  // ran to the end but its divergence monitor fired: metrics kept
  kFailed,    // failed (cell.json says why)
};
const char* CellStatusName(CellStatus status);  // "missing", "done", "diverged", "failed"
// Done or diverged: the cell is finished and is not run again.
inline bool Finished(CellStatus s) { return s == CellStatus::kDone || s == CellStatus::kDiverged; }

// Records a cell whose run ended: a run that exited 0 or diverged is
// evaluated; writes cell.json atomically. Returns the status recorded, or
// the error writing it.
StatusOr<CellStatus> RecordCell(const Cell& cell, const CellRunEnd& end);
// Records a cell whose simulated data is missing or failed (status failed).
StatusOr<CellStatus> RecordDataFailure(const Cell& cell, const DataItem& data,
                                       const std::string& log_tail);

// The status of the cell's cell.json when it holds the plan's hash.
CellStatus ReadCellStatus(const Cell& cell);

}  // namespace rvlio::experiments::ablate

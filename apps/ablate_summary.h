#pragma once
// The summary of an ablation, built only from the cells' cell.json files (so
// `rvlio ablate` and the Snakemake workflow produce the same tables):
//   D/summary.csv         one row per cell (status, exit code, metrics, error)
//   D/table.csv, table.md grouped by sequence x variant (x parameters):
//                         n, failed, diverged, and mean and sample std over
//                         the seeds that finished without diverging
//   D/plots/summary_ablation.png/.pdf  via scripts/rvlio_plot.py when usable
#include <string>

#include "ablate_grid.h"
#include "rvlio/common/status.h"

namespace rvlio::cli::ablate {

struct SummaryResult {
  int cells = 0, done = 0, failed = 0, missing = 0;  // missing: no cell.json with this hash
  int diverged = 0;  // ran to the end but the divergence monitor fired (not in the means)
  std::string table_md;                              // the Markdown table (also in table.md)
  std::string plot_note;                             // "plots: ..." or "plots skipped: why"
};

// Writes the files above (atomically). `plots` false skips the plot script.
StatusOr<SummaryResult> WriteSummary(const Plan& plan, bool plots);

}  // namespace rvlio::cli::ablate

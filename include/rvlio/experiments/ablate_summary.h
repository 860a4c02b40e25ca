#pragma once
// The summary of an ablation, built only from the cells' cell.json files (so
// `rvlio ablate` and the Snakemake workflow produce the same tables):
//   D/summary.csv         one row per cell (status, exit code, metrics, error)
//   D/table.csv, table.md grouped by sequence x variant (x parameters):
//                         n, failed, diverged, and mean and sample std over
//                         the seeds that finished without diverging
// The plot of table.csv (D/plots/summary_ablation.png/.pdf) is drawn by the
// caller with SummaryPlotArgs (scripts/rvlio_plot.py).
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/experiments/ablate_grid.h"

namespace rvlio::experiments::ablate {

struct SummaryResult {
  int cells = 0, done = 0, failed = 0, missing = 0;  // missing: no cell.json with this hash
  int diverged = 0;      // ran to the end but the divergence monitor fired (not in the means)
  std::string table_md;  // the Markdown table (also in table.md)
};

// Writes the files above (atomically).
StatusOr<SummaryResult> WriteSummary(const Plan& plan);

// The plot script's arguments for the summary's bar chart, and the prefix of
// the files it draws (D/plots/summary: summary_ablation.png, .pdf).
std::vector<std::string> SummaryPlotArgs(const Plan& plan, std::string* prefix);

}  // namespace rvlio::experiments::ablate

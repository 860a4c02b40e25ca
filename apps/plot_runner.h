#pragma once
// Runs scripts/rvlio_plot.py from the CLI (compare, ablate) without a shell.
// Plots are optional: when python3 or matplotlib is missing the caller says
// "plots skipped: <message>" and still succeeds.
#include <string>
#include <vector>

namespace rvlio::cli {

struct PlotResult {
  bool ran = false;     // the plot script was started (script and matplotlib found)
  bool ok = false;      // it exited 0
  std::string message;  // why it did not run or failed (first stderr line), or empty
};

// Runs scripts/rvlio_plot.py with the given arguments (subcommand first) if
// python3+matplotlib are usable. The script is found through the environment
// variable RVLIO_PLOT_SCRIPT, else next to the executable
// (../../scripts/rvlio_plot.py for build/bin/rvlio, ../share/rvlio/rvlio_plot.py
// when installed). The interpreter is /usr/bin/python3 if present, else
// python3 on PATH. Availability is probed once per process with
// `rvlio_plot.py check`. The script's stdout is discarded; its stderr is
// captured into `message` on failure.
PlotResult RunPlotScript(const std::vector<std::string>& args);

// The script path RunPlotScript would use, or "" when none is found.
std::string FindPlotScript();

}  // namespace rvlio::cli

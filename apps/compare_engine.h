#pragma once
// `rvlio compare` as a function, so that `rvlio demo` runs it in-process: the
// standard variants on one sequence (IESKF and smoother, RV off and on), then
// `refine` from the best of them, each evaluated against the ground truth,
// tabulated (OUT/compare.csv, .md, .json) and plotted (OUT/plots/).
#include <string>
#include <vector>

#include "rvlio/formats/sensor_stream.h"

namespace rvlio::cli {

struct CompareRequest {
  std::string bag;
  std::string gt;       // ground-truth trajectory (TUM or KITTI, as `rvlio eval`)
  std::string ref_map;  // reference cloud (PCD/PLY): map columns when set (docs/map_eval.md)
  std::string out_dir;  // OUT/<variant>/ for each run
  std::vector<std::string> config_files;
  std::vector<std::string> overrides;  // --set key=value, before each variant's own
  bool refine = true;
  bool plots = true;
  bool quiet = false;  // no step lines; the table and the summary lines remain
  ReadWindow window;   // --start / --duration, for every variant and refine
  // Step numbering of the progress lines, so that `demo` can continue its own
  // ("[k/n] ..."): the first variant is step first_step of total_steps
  // (total_steps 0: compare's own count).
  int first_step = 1;
  int total_steps = 0;
};

// Number of steps (runs) compare makes for `request`: 4 variants + refine.
int CompareSteps(const CompareRequest& request);

// Runs the comparison; returns the exit status (0: at least one variant ran
// without diverging, 1: every variant failed, 3: none ran cleanly but some
// ran to the end and diverged, 2: bad input before any run, with one line on
// stderr and nothing written). Diverged runs are rows with status
// "diverged", their metrics shown but not used as refine's start.
int RunCompare(const CompareRequest& request);

}  // namespace rvlio::cli

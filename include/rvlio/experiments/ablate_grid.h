#pragma once
// Ablation grid files (`rvlio ablate`, target rvlio::experiments): parsing,
// expansion into cells, stable hashes and the machine-readable plan (JSON)
// that workflow/Snakefile consumes. This is the one grid parser of the
// project; the Snakefile never reads the YAML.
//
// Grid YAML (paths relative to the grid file):
//   config: [files]                 common to all cells (optional)
//   set: {key: value}               common overrides (optional)
//   sequences:                      required, non-empty
//     - {name, bag, gt, ref_map, config: [files], set: {..}}        recorded
//     - {name, simulate: {preset, duration, set: {..}}, seeds: [..], ref_map} simulated
//   ref_map (optional): a reference cloud (PCD/PLY, the ground truth's frame);
//     each cell's map.pcd is evaluated against it (map_rms, map_completeness)
//   variants: {name: {key: value, config: [files]}}   (optional; default one "default")
//   parameters: {key: [values] | {from, to, step}}    cartesian product (optional)
//   resources: {cpus, mem_mb, runtime}  per Slurm job of the Snakefile (optional;
//                                   not part of the hash, unused by `rvlio ablate`)
// Cell configuration order: grid config, sequence config, variant config,
// then grid set, sequence set, variant overrides, parameter values.
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "rvlio/common/status.h"

namespace rvlio::experiments::ablate {

// One simulated sequence for one seed, generated into D/data/<id>/.
struct DataItem {
  std::string id;    // "<sequence>_s<seed>_<hash10>"
  std::string hash;  // 16 hex digits of the simulate arguments
  std::string sequence;
  int64_t seed = 0;
  std::string dir;                         // D/data/<id>
  std::vector<std::string> simulate_args;  // "simulate" ... (without the program)
  std::string bag, gt, sensor_config;      // files inside dir
  std::string Marker() const { return dir + "/data.json"; }
};

// One independent `rvlio run` (+ evaluation).
struct Cell {
  std::string id;    // "<sequence>_<variant>[_s<seed>]_<hash10>"
  std::string hash;  // 16 hex digits of the resolved configuration
  std::string sequence;
  bool has_seed = false;
  int64_t seed = 0;
  std::string variant;
  std::vector<std::pair<std::string, std::string>> params;  // key, value text
  std::string label;    // variant, plus " k=v,k=v" when the grid has parameters
  std::string dir;      // D/cells/<id>
  int data_index = -1;  // into Plan::data for a simulated sequence
  std::string bag, gt;  // gt may be empty (no metrics then)
  std::string ref_map;  // reference cloud; empty: no map metrics
  std::vector<std::string> config_files;
  std::vector<std::string> overrides;  // "key=value", applied in order
  std::string RunDir() const { return dir + "/run"; }
  std::string CellJson() const { return dir + "/cell.json"; }
  std::vector<std::string> RunArgs() const;   // "run" ... (without the program)
  std::vector<std::string> EvalArgs() const;  // "eval" ... --json
};

// What one job (a simulation or a cell) asks the scheduler for, from the
// grid's `resources:` block: the Snakefile's threads, mem_mb and runtime.
struct JobResources {
  int cpus = 1;
  int mem_mb = 4000;
  int runtime_min = 120;
};

struct Plan {
  std::string grid_path;
  std::string out_dir;
  std::vector<std::string> param_keys;  // in grid order
  std::vector<DataItem> data;
  std::vector<Cell> cells;
  JobResources resources;
  bool HasRefMap() const;  // some cell has a ref_map: the tables get map columns
  bool HasSimulated() const;  // some cell runs on simulated data: the tables get detection columns
};

// Cells a grid may expand to unless the caller allows more (`rvlio ablate
// --max-cells N`): each range has at most 10000 values, but their product is
// unbounded, and a plan of 400,000 cells takes a minute and 280 MB to build
// before its first run (a cell is a full run: 10000 of them are days).
constexpr int64_t kDefaultMaxCells = 10000;

// Reads and expands the grid. Every error is InvalidInput with one line that
// starts with the grid file (and line) and names the key. A grid of more than
// `max_cells` cells is refused before it is expanded.
StatusOr<Plan> LoadPlan(const std::string& grid_path, const std::string& out_dir,
                        int64_t max_cells = kDefaultMaxCells);

// The plan as JSON text (plan.json, `rvlio ablate --plan`): {grid, out,
// param_keys, resources: {cpus, mem_mb, runtime}, data: [...], cells: [...]}.
std::string PlanJsonText(const Plan& plan);


// Expands a {from, to, step} range inclusively without float drift: values
// from + i*step printed with 12 significant digits (integers when all three
// are integers). Errors: zero step, empty range, more than 10000 values.
StatusOr<std::vector<std::string>> ExpandRange(const std::string& from, const std::string& to,
                                               const std::string& step);

}  // namespace rvlio::experiments::ablate

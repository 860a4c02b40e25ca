// End-to-end tests of `rvlio ablate` (grid parsing through --plan, real runs,
// resume, failing cells, the summary) and of workflow/Snakefile.
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli/cli_util.h"

namespace rvlio::testing_cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// Rows of a CSV without quoted commas in the compared columns: header -> value.
std::vector<std::map<std::string, std::string>> ReadCsv(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
  auto split = [](const std::string& l) {
    std::vector<std::string> f;
    std::stringstream ss(l);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    if (!l.empty() && l.back() == ',') f.push_back("");
    return f;
  };
  if (std::getline(in, line)) header = split(line);
  while (std::getline(in, line)) {
    const auto f = split(line);
    std::map<std::string, std::string> row;
    for (size_t i = 0; i < header.size() && i < f.size(); ++i) row[header[i]] = f[i];
    rows.push_back(row);
  }
  return rows;
}

const std::map<std::string, std::string>* FindRow(
    const std::vector<std::map<std::string, std::string>>& rows, const std::string& sequence,
    const std::string& variant) {
  for (const auto& r : rows)
    if (r.at("sequence") == sequence && r.at("variant") == variant) return &r;
  return nullptr;
}

int64_t MtimeNs(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return -1;
  return static_cast<int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
}

// ---------------------------------------------------------------------------
// Grid parsing and expansion (--plan runs nothing)
// ---------------------------------------------------------------------------

class AblatePlanTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = MakeTempDir("rvlio_ablate_plan");
    ASSERT_FALSE(dir_.empty());
    WriteText(dir_ + "/rec.bag", "not read at plan time");
    WriteText(dir_ + "/rec_gt.tum", "0 0 0 0 0 0 0 1\n");
    WriteText(dir_ + "/common.yaml", "rv:\n  k0: 2.0\n");
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Grid(const std::string& body, const std::string& name = "grid.yaml") {
    WriteText(dir_ + "/" + name, body);
    return dir_ + "/" + name;
  }
  ToolRun Plan(const std::string& grid, const std::string& out = "") {
    return RunTool(
        "ablate --grid " + grid + " --out " + (out.empty() ? dir_ + "/out" : out) + " --plan",
        dir_);
  }
  json PlanJson(const std::string& grid) {
    const ToolRun r = Plan(grid);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return json::parse(r.out, nullptr, false);
  }
  std::string dir_;
};

constexpr const char* kGrid = R"(
config: [common.yaml]
set: {rv.activation_ratio: 0.8}
sequences:
  - name: sim
    simulate: {preset: tunnel, duration: 5, set: {lidar.columns: 512}}
    seeds: {from: 1, to: 3, step: 1}
  - name: rec
    bag: rec.bag
    gt: rec_gt.tum
variants:
  off: {rv: {enabled: false}}
  on: {}
parameters:
  rv.eps0: {from: 0.1, to: 0.5, step: 0.1}
  rv.eps1: [0.05, 0.1]
)";

TEST_F(AblatePlanTest, ExpandsListsRangesAndTheProduct) {
  const json plan = PlanJson(Grid(kGrid));
  ASSERT_TRUE(plan.is_object());
  // 3 seeds + 1 recorded sequence, 2 variants, 5 x 2 parameter values.
  EXPECT_EQ(plan["cells"].size(), 4u * 2u * 5u * 2u);
  ASSERT_EQ(plan["data"].size(), 3u);
  EXPECT_EQ(plan["param_keys"], json({"rv.eps0", "rv.eps1"}));
  std::set<std::string> eps0, seeds, ids;
  for (const json& c : plan["cells"]) {
    eps0.insert(c["params"]["rv.eps0"].get<std::string>());
    if (!c["seed"].is_null()) seeds.insert(std::to_string(c["seed"].get<int>()));
    ids.insert(c["id"].get<std::string>());
  }
  EXPECT_EQ(eps0,
            (std::set<std::string>{"0.1", "0.2", "0.3", "0.4", "0.5"}));  // no 0.30000000000000004
  EXPECT_EQ(seeds, (std::set<std::string>{"1", "2", "3"}));
  EXPECT_EQ(ids.size(), plan["cells"].size());

  // Configuration order: grid config, sequence config, variant; then grid set,
  // variant overrides, parameters.
  const json& c = plan["cells"][0];
  EXPECT_EQ(c["sequence"], "sim");
  EXPECT_EQ(c["variant"], "off");
  const std::vector<std::string> argv = c["run_argv"];
  std::vector<std::string> sets, configs;
  for (size_t i = 0; i + 1 < argv.size(); ++i) {
    if (argv[i] == "--set") sets.push_back(argv[i + 1]);
    if (argv[i] == "--config") configs.push_back(argv[i + 1]);
  }
  EXPECT_EQ(sets, (std::vector<std::string>{"rv.activation_ratio=0.8", "rv.enabled=false",
                                            "rv.eps0=0.1", "rv.eps1=0.05"}));
  ASSERT_EQ(configs.size(), 2u);
  EXPECT_EQ(configs[0], dir_ + "/common.yaml");  // relative to the grid file
  EXPECT_EQ(configs[1], plan["data"][0]["config"]);
  EXPECT_EQ(argv[0], "run");
  EXPECT_EQ(c["eval_argv"][0], "eval");
  const std::vector<std::string> sim = plan["data"][0]["simulate_argv"];
  EXPECT_EQ(sim[0], "simulate");
  EXPECT_NE(std::find(sim.begin(), sim.end(), "lidar.columns=512"), sim.end());
  EXPECT_EQ(plan["cells"].back()["sequence"], "rec");
  EXPECT_TRUE(plan["cells"].back()["seed"].is_null());
  EXPECT_EQ(plan["cells"].back()["run_argv"][2], dir_ + "/rec.bag");
}

// The grids shipped in config/grids plan without error and have the number
// of cells their comments and the README quote.
TEST_F(AblatePlanTest, ShippedGridsPlanWithTheDocumentedCellCounts) {
  const std::string grids = std::string(RVLIO_SOURCE_DIR) + "/config/grids/";
  for (const auto& [name, cells] : std::vector<std::pair<std::string, size_t>>{
           {"rv_ablation.yaml", 36},
           {"rv_defaults.yaml", 217},
           {"rv_gain.yaml", 115},
           {"degeneracy.yaml", 60}}) {
    const json plan = PlanJson(grids + name);
    ASSERT_TRUE(plan.is_object()) << name;
    EXPECT_EQ(plan["cells"].size(), cells) << name;
  }
}

// The degeneracy comparison: every method on the IESKF and on the smoother,
// each on every preset and seed, with the method and backend set.
TEST_F(AblatePlanTest, DegeneracyGridHasEveryMethodOnEveryPresetAndSeed) {
  const json plan = PlanJson(std::string(RVLIO_SOURCE_DIR) + "/config/grids/degeneracy.yaml");
  ASSERT_TRUE(plan.is_object());
  EXPECT_EQ(plan["data"].size(), 6u);  // 3 presets x 2 seeds
  std::set<std::string> cells;
  for (const json& c : plan["cells"]) {
    std::string method, backend = "ieskf";
    const std::vector<std::string> argv = c["run_argv"];
    for (size_t i = 0; i + 1 < argv.size(); ++i) {
      if (argv[i] != "--set") continue;
      if (argv[i + 1].rfind("degeneracy.method=", 0) == 0) method = argv[i + 1].substr(18);
      if (argv[i + 1].rfind("backend=", 0) == 0) backend = argv[i + 1].substr(8);
    }
    EXPECT_EQ(c["variant"].get<std::string>(), backend + "_" + method);
    cells.insert(c["sequence"].get<std::string>() + "/" + backend + "_" + method + "/" +
                 std::to_string(c["seed"].get<int>()));
  }
  std::set<std::string> expected;
  for (const char* preset : {"tunnel", "corridor", "featureless"})
    for (const char* variant : {"ieskf_none", "ieskf_rv", "ieskf_remap", "ieskf_localizability",
                                "ieskf_regularized", "smoother_none", "smoother_rv",
                                "smoother_remap", "smoother_localizability",
                                "smoother_regularized"})
      for (const char* seed : {"1", "2"})
        expected.insert(std::string(preset) + "/" + variant + "/" + seed);
  EXPECT_EQ(cells, expected);
  EXPECT_EQ(plan["cells"].size(), expected.size());
}

TEST_F(AblatePlanTest, PlanIsStableAndTheHashFollowsTheConfiguration) {
  const std::string grid = Grid(kGrid);
  const ToolRun a = Plan(grid), b = Plan(grid);
  ASSERT_EQ(a.exit_code, 0) << a.err;
  EXPECT_EQ(a.out, b.out);
  const json before = json::parse(a.out);

  // The hash does not depend on the output folder.
  const json other_out = json::parse(Plan(grid, dir_ + "/elsewhere").out);
  EXPECT_EQ(other_out["cells"][7]["hash"], before["cells"][7]["hash"]);

  // Changing one parameter value changes exactly the cells that use it.
  std::string changed = kGrid;
  changed.replace(changed.find("[0.05, 0.1]"), 11, "[0.05, 0.09]");
  const json after = PlanJson(Grid(changed, "grid2.yaml"));
  ASSERT_EQ(after["cells"].size(), before["cells"].size());
  for (size_t i = 0; i < before["cells"].size(); ++i) {
    const bool uses = before["cells"][i]["params"]["rv.eps1"] == "0.1";
    EXPECT_EQ(before["cells"][i]["hash"] != after["cells"][i]["hash"], uses) << i;
  }
  // So does the content of a config file.
  WriteText(dir_ + "/common.yaml", "rv:\n  k0: 3.0\n");
  const json edited = PlanJson(grid);
  EXPECT_NE(edited["cells"][0]["hash"], before["cells"][0]["hash"]);
}

// A sequence's ref_map reaches its cells (and only its cells' hashes).
TEST_F(AblatePlanTest, RefMapReachesTheCellsOfItsSequence) {
  WriteText(dir_ + "/ref.pcd", "not read at plan time");
  const json before = PlanJson(Grid(kGrid));
  std::string with = kGrid;
  with.replace(with.find("    gt: rec_gt.tum\n"), 19, "    gt: rec_gt.tum\n    ref_map: ref.pcd\n");
  const json after = PlanJson(Grid(with, "m.yaml"));
  ASSERT_EQ(after["cells"].size(), before["cells"].size());
  for (size_t i = 0; i < after["cells"].size(); ++i) {
    const bool rec = after["cells"][i]["sequence"] == "rec";
    EXPECT_EQ(after["cells"][i]["ref_map"], rec ? dir_ + "/ref.pcd" : "") << i;
    EXPECT_EQ(after["cells"][i]["hash"] != before["cells"][i]["hash"], rec) << i;
  }
  std::string missing = kGrid;
  missing.replace(missing.find("    gt: rec_gt.tum\n"), 19, "    gt: rec_gt.tum\n    ref_map: no.pcd\n");
  const ToolRun r = Plan(Grid(missing, "bad.yaml"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("sequences[1].ref_map: file not found"), std::string::npos) << r.err;
}

// The grid's `resources:` block reaches the plan (the Snakefile's Slurm jobs)
// and does not change any cell: it is not part of the configuration hash.
TEST_F(AblatePlanTest, ResourcesReachThePlanWithoutChangingTheCells) {
  const json defaults = PlanJson(Grid(kGrid));
  ASSERT_TRUE(defaults.is_object());
  EXPECT_EQ(defaults["resources"], json({{"cpus", 1}, {"mem_mb", 4000}, {"runtime", 120}}));
  const json sized = PlanJson(
      Grid(std::string(kGrid) + "resources: {cpus: 2, mem_mb: 900, runtime: 15}\n", "r.yaml"));
  ASSERT_TRUE(sized.is_object());
  EXPECT_EQ(sized["resources"], json({{"cpus", 2}, {"mem_mb", 900}, {"runtime", 15}}));
  const json partial = PlanJson(Grid(std::string(kGrid) + "resources:\n  mem_mb: 700\n", "p.yaml"));
  EXPECT_EQ(partial["resources"], json({{"cpus", 1}, {"mem_mb", 700}, {"runtime", 120}}));
  ASSERT_EQ(sized["cells"].size(), defaults["cells"].size());
  for (size_t i = 0; i < defaults["cells"].size(); ++i)
    EXPECT_EQ(sized["cells"][i]["id"], defaults["cells"][i]["id"]) << i;
}

TEST_F(AblatePlanTest, BadGridsStopWithExit2AndOneLineNamingFileAndKey) {
  const std::string seq = "sequences:\n  - {name: r, bag: rec.bag}\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"sequences: []\n", "sequences"},
      {seq + "paramters: {rv.eps0: [0.1]}\n", "paramters: unknown key"},
      {"sequences:\n  - {name: r, bagg: rec.bag}\n", "sequences[0].bagg: unknown key"},
      {"sequences:\n  - {name: r, bag: missing.bag}\n", "sequences[0].bag: file not found"},
      {seq + "parameters:\n  rv.eps0: {from: 0.1, to: 0.5, step: 0}\n", "parameters.rv.eps0"},
      {seq + "parameters:\n  rv.eps0: {from: 0.5, to: 0.1, step: 0.1}\n", "empty range"},
      {seq + "parameters:\n  rv.eps0: {from: 0.1, to: 0.5}\n", "parameters.rv.eps0.step"},
      {seq + "variants:\n  v: {rv.epss0: 1}\n", "rv.epss0"},
      {seq + "variants:\n  v: {backend: smoother, degeneracy.method: remapp}\n",
       "degeneracy.method"},
      {seq + "config: [nope.yaml]\n", "config: file not found"},
      {"sequences:\n  - {name: s, simulate: {preset: tunel}}\n", "sequences[0].simulate.preset"},
      {"sequences:\n  - {name: s, simulate: {preset: tunnel}, seeds: [-1]}\n", "seeds"},
      {seq + "resources: {cpu: 2}\n", "resources.cpu: unknown key"},
      {seq + "resources: {cpus: 0}\n", "resources.cpus: '0' is not a whole number of CPUs"},
      {seq + "resources: {mem_mb: 1.5}\n", "resources.mem_mb: '1.5' is not a whole number"},
      {seq + "resources: {runtime: [1]}\n", "resources.runtime"},
      {seq + "resources: 4\n", "resources: expected a mapping"},
  };
  for (const auto& [body, expected] : cases) {
    const std::string grid = Grid(body, "bad.yaml");
    const ToolRun r = Plan(grid);
    EXPECT_EQ(r.exit_code, 2) << body;
    EXPECT_NE(r.err.find(grid), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(expected), std::string::npos)
        << "expected '" << expected << "' in " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty());
  }
  const ToolRun jobs =
      RunTool("ablate --grid " + Grid(seq) + " --out " + dir_ + "/o --jobs 0", dir_);
  EXPECT_EQ(jobs.exit_code, 2);
  EXPECT_NE(jobs.err.find("--jobs"), std::string::npos);
}

// A grid larger than the cell limit is refused before it is expanded (the
// product of the ranges is unbounded); --max-cells allows it; a run states
// the number of cells before it starts.
TEST_F(AblatePlanTest, GridBeyondTheCellLimitIsRefusedUnlessAllowedAndTheCountIsStated) {
  const std::string seq = "sequences:\n  - {name: r, bag: rec.bag}\n";
  const std::string huge = Grid(seq + "parameters:\n  rv.k0: {from: 1, to: 10000, step: 1}\n"
                                      "  rv.eps0: {from: 1, to: 10000, step: 1}\n",
                                "huge.yaml");
  ToolRun r = Plan(huge);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("the grid has 1e+08 cells"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--max-cells"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;

  const std::string four = Grid(seq + "parameters:\n  rv.k0: [1, 2, 3, 4]\n", "four.yaml");
  r = RunTool("ablate --grid " + four + " --out " + dir_ + "/o --plan --max-cells 3", dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("the grid has 4 cells"), std::string::npos) << r.err;
  r = RunTool("ablate --grid " + four + " --out " + dir_ + "/o --plan --max-cells 4", dir_);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out, nullptr, false)["cells"].size(), 4u);
  r = RunTool("ablate --grid " + four + " --out " + dir_ + "/o --plan --max-cells 0", dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;

  // rec.bag is not a bag: each cell fails at once (recorded), after the count.
  const std::string two = Grid(seq + "parameters:\n  rv.k0: [1, 2]\n", "two.yaml");
  r = RunTool("ablate --grid " + two + " --out " + dir_ + "/run --no-plots", dir_);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("rvlio ablate: the grid has 2 cells", 0), 0u) << r.out;
}

// ---------------------------------------------------------------------------
// Real runs: tiny.yaml's tunnel (2 seeds x 2 variants) plus a corrupt bag
// ---------------------------------------------------------------------------

std::string TinyGrid() { return std::string(RVLIO_SOURCE_DIR) + "/config/grids/tiny.yaml"; }

// The checks of one ablation run, in the order a user sees them; one test so
// that ctest (one process per test) runs the ablation once.
void CheckCells(const ToolRun& first, const json& plan) {
  EXPECT_NE(first.out.find("6 cells: 0 already done, 6 run now (4 done, 2 failed)"),
            std::string::npos)
      << first.out;
  EXPECT_NE(first.err.find("[6/6] cell"), std::string::npos) << first.err;  // plain progress lines
  int done = 0, failed = 0;
  for (const json& c : plan["cells"]) {
    const json r = json::parse(ReadFile(c["cell_json"]), nullptr, false);
    ASSERT_TRUE(r.is_object()) << c["cell_json"];
    EXPECT_EQ(r["hash"], c["hash"]);
    if (c["sequence"] == "broken") {
      ++failed;
      EXPECT_EQ(r["status"], "failed");
      EXPECT_EQ(r["exit_code"], 2);
      EXPECT_NE(r["stderr_tail"].get<std::string>().find("rvlio run: error"), std::string::npos);
      EXPECT_NE(r["error"].get<std::string>().find("exited with status 2"), std::string::npos);
    } else {
      ++done;
      EXPECT_EQ(r["status"], "done") << r.dump();
      EXPECT_EQ(r["exit_code"], 0);
      for (const char* m : {"ate_rmse", "rpe_rmse", "axis_rmse", "axis_max", "end_point", "ms_per_scan"}) {
        ASSERT_TRUE(r["metrics"][m].is_number()) << m;
        EXPECT_GT(r["metrics"][m].get<double>(), 0.0) << m;
      }
      EXPECT_LT(r["metrics"]["ate_rmse"].get<double>(), 0.5);  // a 6 s tunnel stays localized
    }
  }
  EXPECT_EQ(done, 4);
  EXPECT_EQ(failed, 2);
}

void CheckTable(const json& plan, const std::string& out) {
  std::map<std::string, std::vector<double>> values;  // variant/metric -> values
  for (const json& c : plan["cells"]) {
    if (c["sequence"] != "tunnel") continue;
    const json r = json::parse(ReadFile(c["cell_json"]));
    for (const char* m : {"ate_rmse", "rpe_rmse", "axis_rmse", "axis_max", "end_point", "ms_per_scan"})
      values[c["variant"].get<std::string>() + "/" + m].push_back(r["metrics"][m].get<double>());
  }
  const auto rows = ReadCsv(out + "/table.csv");
  ASSERT_EQ(rows.size(), 4u);  // tunnel x 2 variants, broken x 2 variants
  for (const char* variant : {"rv_off", "rv_on"}) {
    const auto* row = FindRow(rows, "tunnel", variant);
    ASSERT_NE(row, nullptr) << variant;
    EXPECT_EQ(row->at("n"), "2");
    EXPECT_EQ(row->at("failed"), "0");
    for (const char* m : {"ate_rmse", "rpe_rmse", "axis_rmse", "axis_max", "end_point", "ms_per_scan"}) {
      const auto& v = values[std::string(variant) + "/" + m];
      ASSERT_EQ(v.size(), 2u);
      const double mean = 0.5 * (v[0] + v[1]);
      const double std = std::abs(v[0] - v[1]) / std::sqrt(2.0);  // sample std of two values
      EXPECT_NEAR(std::stod(row->at(std::string(m) + "_mean")), mean, 1e-9 * (1 + mean)) << m;
      EXPECT_NEAR(std::stod(row->at(std::string(m) + "_std")), std, 1e-9 * (1 + std)) << m;
    }
  }
  const auto* broken = FindRow(rows, "broken", "rv_on");
  ASSERT_NE(broken, nullptr);
  EXPECT_EQ(broken->at("n"), "0");
  EXPECT_EQ(broken->at("failed"), "1");
  EXPECT_EQ(broken->at("ate_rmse_mean"), "");
  EXPECT_EQ(ReadCsv(out + "/summary.csv").size(), 6u);
  EXPECT_NE(ReadFile(out + "/table.md").find("| tunnel | rv_on | 2 | 0 |"), std::string::npos);
  // report.html (docs/report.md): the page's data holds one table row per cell.
  const std::string report = ReadFile(out + "/report.html");
  const std::string open = "<script id=\"rvlio-data\" type=\"application/json\">";
  const size_t begin = report.find(open);
  ASSERT_NE(begin, std::string::npos);
  const json page = json::parse(report.substr(begin + open.size(),
                                              report.find("</script>", begin) - begin - open.size()),
                                nullptr, false);
  ASSERT_TRUE(page.is_object());
  EXPECT_EQ(page["kind"], "ablate");
  EXPECT_EQ(page["table"]["rows"].size(), 6u);
}

// Simulated cells: the degenerate fraction is the summary's, and the
// detection scores are those of `rvlio eval --degeneracy` on the cell's run
// against its simulation (null where undefined); the table averages them.
void CheckDetection(const json& plan, const std::string& dir,
                    const std::vector<std::map<std::string, std::string>>& rows) {
  std::map<std::string, std::vector<double>> precision;  // variant -> defined values
  for (const json& c : plan["cells"]) {
    if (c["sequence"] != "tunnel") continue;
    const json m = json::parse(ReadFile(c["cell_json"]))["metrics"];
    const std::string run = c["dir"].get<std::string>() + "/run";
    const json summary = json::parse(ReadFile(run + "/summary.json"));
    EXPECT_DOUBLE_EQ(m["degenerate_fraction"].get<double>(),
                     summary["degenerate_scans"].get<double>() / summary["scan_count"].get<double>());
    const std::string truth = c["eval_argv"][2].get<std::string>();  // --gt DATA/tunnel_gt.tum
    const ToolRun eval = RunTool("eval --degeneracy " + run + " --truth " +
                                     fs::path(truth).parent_path().string() + " --json", dir);
    ASSERT_EQ(eval.exit_code, 0) << eval.err;
    const json scores = json::parse(eval.out);
    for (const char* key : {"precision", "recall"}) {
      const json& mine = m[std::string("detect_") + key];
      ASSERT_EQ(mine.is_null(), scores[key].is_null()) << key << " " << eval.out;
      if (mine.is_number()) {
        EXPECT_DOUBLE_EQ(mine.get<double>(), scores[key].get<double>()) << key;
      }
    }
    if (scores["precision"].is_number()) {
      precision[c["variant"]].push_back(scores["precision"].get<double>());
    }
  }
  // rv_on flags scans (RV active), so its precision is defined on both seeds;
  // rv_off flags none.
  ASSERT_EQ(precision["rv_on"].size(), 2u);
  EXPECT_TRUE(precision["rv_off"].empty());
  const auto* row = FindRow(rows, "tunnel", "rv_on");
  ASSERT_NE(row, nullptr);
  EXPECT_NEAR(std::stod(row->at("detect_precision_mean")),
              0.5 * (precision["rv_on"][0] + precision["rv_on"][1]), 1e-9);
  EXPECT_EQ(FindRow(rows, "tunnel", "rv_off")->at("detect_precision_mean"), "");
}

void CheckResume(const json& plan, const std::string& dir) {
  const std::string out = dir + "/out", grid = dir + "/grid.yaml";
  std::map<std::string, int64_t> mtimes;
  for (const json& c : plan["cells"]) mtimes[c["cell_json"]] = MtimeNs(c["cell_json"]);
  const ToolRun again =
      RunTool("ablate --grid " + grid + " --out " + out + " --jobs 2 --no-plots", dir);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find("6 cells: 4 already done, 2 run now (0 done, 2 failed)"),
            std::string::npos)
      << again.out;
  for (const json& c : plan["cells"]) {
    if (c["sequence"] == "tunnel") {
      EXPECT_EQ(MtimeNs(c["cell_json"]), mtimes[c["cell_json"]]);
    }
  }
  // --cell on a finished cell runs nothing; an unknown id is bad input.
  const std::string id = plan["cells"][0]["id"];
  const ToolRun one = RunTool("ablate --grid " + grid + " --out " + out + " --cell " + id, dir);
  EXPECT_EQ(one.exit_code, 0);
  EXPECT_NE(one.out.find(id + " already done"), std::string::npos) << one.out;
  const ToolRun unknown = RunTool("ablate --grid " + grid + " --out " + out + " --cell nope", dir);
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("no cell or data 'nope'"), std::string::npos);
}

class AblateRunTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = MakeTempDir("rvlio_ablate_run");
    ASSERT_FALSE(dir_.empty());
    // The tiny grid's sequence and variants (same cell hashes) and a bag
    // that `rvlio run` rejects.
    std::string grid = ReadFile(TinyGrid());
    const size_t at = grid.find("variants:");
    ASSERT_NE(at, std::string::npos);
    grid.insert(at, "  - name: broken\n    bag: broken.bag\n");
    WriteText(dir_ + "/broken.bag", std::string(4096, 'x'));
    WriteText(dir_ + "/grid.yaml", grid);
    first_ = RunTool("ablate --grid " + dir_ + "/grid.yaml --out " + Out() + " --jobs 2 --no-plots",
                     dir_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string Out() { return dir_ + "/out"; }
  static json PlanOf() {
    return json::parse(
        RunTool("ablate --grid " + dir_ + "/grid.yaml --out " + Out() + " --plan", dir_).out);
  }
  static inline std::string dir_;
  static inline ToolRun first_;
};

TEST_F(AblateRunTest, RecordsFailuresSummarizesOverSeedsAndResumes) {
  ASSERT_EQ(first_.exit_code, 0) << first_.err;
  const json plan = PlanOf();
  ASSERT_EQ(plan["cells"].size(), 6u);
  CheckCells(first_, plan);
  CheckTable(plan, Out());
  CheckDetection(plan, dir_, ReadCsv(Out() + "/table.csv"));
  CheckResume(plan, dir_);
}

// ---------------------------------------------------------------------------
// The Snakemake workflow on the same grid
// ---------------------------------------------------------------------------

std::string FindSnakemake() {
  for (const char* p : {"/usr/bin/snakemake", "/usr/local/bin/snakemake"})
    if (fs::exists(p)) return p;
  return "";
}

TEST_F(AblateRunTest, SnakemakeWorkflowGivesTheSameTable) {
  ASSERT_EQ(first_.exit_code, 0) << first_.err;
  const std::string snakemake = FindSnakemake();
  if (snakemake.empty()) GTEST_SKIP() << "snakemake is not installed (apt-get install snakemake)";
  const std::string work = dir_ + "/sm";
  fs::create_directories(work);
  const std::string base =
      snakemake + " -s " + RVLIO_SOURCE_DIR + "/workflow/Snakefile -j 2 --directory " + work +
      " --config grid=" + TinyGrid() + " out=" + work + "/out rvlio=" + RVLIO_BIN + " plots=false";
  const std::string out = work + "/stdout.txt", err = work + "/stderr.txt";
  auto run = [&](const std::string& extra) {
    const int status = std::system((base + " " + extra + " >" + out + " 2>" + err).c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  ASSERT_EQ(run("-n"), 0) << ReadFile(err);
  const std::string dry = ReadFile(out) + ReadFile(err);
  for (const char* job :
       {"data             2", "cell             4", "summarize        1", "total            8"})
    EXPECT_NE(dry.find(job), std::string::npos) << job << " in\n" << dry;
  EXPECT_FALSE(fs::exists(work + "/out/table.csv"));

  ASSERT_EQ(run(""), 0) << ReadFile(err);
  const auto sm = ReadCsv(work + "/out/table.csv");
  const auto ab = ReadCsv(Out() + "/table.csv");
  ASSERT_EQ(sm.size(), 2u);
  for (const char* variant : {"rv_off", "rv_on"}) {
    const auto* a = FindRow(ab, "tunnel", variant);
    const auto* s = FindRow(sm, "tunnel", variant);
    ASSERT_TRUE(a && s) << variant;
    EXPECT_EQ(s->at("n"), "2");
    for (const char* m : {"ate_rmse", "rpe_rmse", "axis_rmse", "axis_max", "end_point"})
      for (const char* stat : {"_mean", "_std"}) {
        const std::string col = std::string(m) + stat;
        EXPECT_NEAR(std::stod(s->at(col)), std::stod(a->at(col)), 1e-9) << variant << " " << col;
      }
  }
}

}  // namespace
}  // namespace rvlio::testing_cli

// End to end: `rvlio compare` on a short simulated tunnel (10 s, 512 columns,
// seed 3, made once per suite). One test runs the full compare (four variants,
// refine from the best, plots) and checks all its outputs (ctest runs each test
// in its own process, so one full compare per test would multiply the time);
// failure handling runs with --no-refine and most variants blocked.
#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli/cli_util.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;
using testing_cli::EvalJson;
using testing_cli::MakeTempDir;
using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

const std::vector<std::string> kVariants = {"ieskf_rv_off", "ieskf_rv_on", "smoother_rv_off",
                                            "smoother_rv_on", "refine"};
const std::vector<std::string> kCsvColumns = {
    "variant", "label",       "status",      "exit_code",   "init",        "scans",
    "ate_rmse_m", "rpe_rmse_m", "axis_max_m", "end_point_m", "ms_per_scan", "real_time_factor"};
constexpr double kEvalTolerance = 1e-6;  // m: CSV vs `rvlio eval --json`

using CsvRow = std::map<std::string, std::string>;

// Splits one CSV line with RFC 4180 quoting ("a, b" and "" inside quotes).
std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      fields.back() += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return fields;
}

// Header and rows of a CSV file; every row must have the header's width.
std::vector<CsvRow> ReadCsv(const std::string& path, std::vector<std::string>* header) {
  std::istringstream in(ReadFile(path));
  std::string line;
  std::vector<CsvRow> rows;
  if (!std::getline(in, line)) return rows;
  *header = SplitCsvLine(line);
  while (std::getline(in, line)) {
    const std::vector<std::string> fields = SplitCsvLine(line);
    EXPECT_EQ(fields.size(), header->size()) << line;
    CsvRow row;
    for (size_t i = 0; i < fields.size() && i < header->size(); ++i) row[(*header)[i]] = fields[i];
    rows.push_back(row);
  }
  return rows;
}

double Number(const CsvRow& row, const std::string& column) {
  const auto it = row.find(column);
  if (it == row.end() || it->second.empty()) return NAN;
  return std::stod(it->second);
}

size_t Lines(const std::string& text) { return std::count(text.begin(), text.end(), '\n'); }

bool PlotScriptUsable() {
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  const std::string cmd = python + " " + RVLIO_SOURCE_DIR +
                          "/scripts/rvlio_plot.py check >/dev/null 2>&1";
  return std::system(cmd.c_str()) == 0;
}

// Sets an environment variable for the lifetime of the object.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old, had_ = true;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() { had_ ? setenv(name_, old_.c_str(), 1) : unsetenv(name_); }

 private:
  const char* name_;
  std::string old_;
  bool had_ = false;
};

class CompareTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = MakeTempDir("rvlio_compare");
    ASSERT_FALSE(dir_.empty());
    const ToolRun sim = testing_cli::CachedSimulate(
        "--preset tunnel --seed 3 --duration 10 --set lidar.columns=512", dir_ + "/data", dir_);
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static std::string Bag() { return dir_ + "/data/tunnel.bag"; }
  static std::string Truth() { return dir_ + "/data/tunnel_gt.tum"; }
  static std::string CompareArgs(const std::string& out, const std::string& extra = "") {
    return "compare --bag " + Bag() + " --gt " + Truth() + " --config " + dir_ +
           "/data/tunnel.yaml --out " + out + " " + extra;
  }
  // Exit 2, exactly one line on stderr containing `part`, nothing on stdout and
  // no output folder: nothing ran.
  static void ExpectBadInput(const std::string& args, const std::string& part) {
    const std::string out = dir_ + "/bad";
    fs::remove_all(out);
    const ToolRun r = RunTool(args, dir_);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(Lines(r.err), 1u) << r.err;
    EXPECT_EQ(r.err.rfind("rvlio compare: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(part), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "");
    EXPECT_FALSE(fs::exists(out + "/compare.csv"));
    EXPECT_FALSE(fs::exists(out + "/ieskf_rv_off"));
  }

  static inline std::string dir_;
};

void CheckOutputs(const std::string& out, const ToolRun& full) {
  SCOPED_TRACE("outputs");
  for (const std::string& v : kVariants) {
    for (const char* file : {"trajectory.tum", "map.pcd", "summary.json"})
      EXPECT_TRUE(fs::is_regular_file(out + "/" + v + "/" + file)) << v << "/" << file;
    EXPECT_NE(full.out.find(v), std::string::npos) << full.out;
  }
  std::vector<std::string> header;
  const std::vector<CsvRow> rows = ReadCsv(out + "/compare.csv", &header);
  EXPECT_EQ(header, kCsvColumns);
  ASSERT_EQ(rows.size(), kVariants.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i].at("variant"), kVariants[i]);
    EXPECT_EQ(rows[i].at("status"), "ok");
    EXPECT_EQ(rows[i].at("exit_code"), "0");
    EXPECT_GE(Number(rows[i], "scans"), 80) << kVariants[i];  // 10 s at 10 Hz, after start-up
    EXPECT_LE(Number(rows[i], "scans"), 101) << kVariants[i];
  }
  // Markdown: header, separator, one line per variant, then the explanation.
  const std::string md = ReadFile(out + "/compare.md");
  EXPECT_EQ(md.rfind("| variant | ATE [m] | RPE [m] | along-axis max [m] | end-point [m] | "
                     "ms/scan | real-time factor |\n|---|---|---|---|---|---|---|\n", 0), 0u)
      << md;
  EXPECT_EQ(std::count(md.begin(), md.end(), '|'), 8 * 7) << md;
  EXPECT_NE(md.find("| refine (from "), std::string::npos) << md;
  // No temporary files left behind.
  for (const auto& entry : fs::directory_iterator(out))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

void CheckNumbersEqualEval(const std::string& out, const std::string& truth,
                           const std::string& scratch) {
  SCOPED_TRACE("numbers vs rvlio eval --json");
  std::vector<std::string> header;
  const std::vector<CsvRow> rows = ReadCsv(out + "/compare.csv", &header);
  ASSERT_EQ(rows.size(), kVariants.size());
  std::ifstream json_in(out + "/compare.json");
  const nlohmann::json summary = nlohmann::json::parse(json_in, nullptr, false);
  ASSERT_FALSE(summary.is_discarded());
  ASSERT_EQ(summary["variants"].size(), kVariants.size());
  EXPECT_EQ(summary["align"], "se3");
  for (size_t i = 0; i < rows.size(); ++i) {
    const std::string v = rows[i].at("variant");
    const nlohmann::json e = EvalJson(truth, out + "/" + v + "/trajectory.tum", scratch);
    ASSERT_TRUE(e.is_object()) << v;
    EXPECT_NEAR(Number(rows[i], "ate_rmse_m"), e["ape"]["rmse"].get<double>(), kEvalTolerance) << v;
    EXPECT_NEAR(Number(rows[i], "rpe_rmse_m"), e["rpe"]["rmse"].get<double>(), kEvalTolerance) << v;
    EXPECT_NEAR(Number(rows[i], "axis_max_m"), e["along_axis"]["max"].get<double>(),
                kEvalTolerance) << v;
    EXPECT_NEAR(Number(rows[i], "end_point_m"), e["end_point_error"].get<double>(),
                kEvalTolerance) << v;
    const nlohmann::json& row_json = summary["variants"][i];
    EXPECT_EQ(row_json["variant"], v);
    EXPECT_NEAR(row_json["ate_rmse_m"].get<double>(), e["ape"]["rmse"].get<double>(),
                kEvalTolerance) << v;
    // Speed comes from the run's own summary.json.
    std::ifstream in(out + "/" + v + "/summary.json");
    const nlohmann::json run = nlohmann::json::parse(in, nullptr, false);
    ASSERT_TRUE(run.is_object()) << v;
    EXPECT_EQ(Number(rows[i], "scans"), run["scan_count"].get<double>()) << v;
    if (v == "refine") {
      const double refine_s = run["time_s"]["refine"].get<double>();
      EXPECT_NEAR(Number(rows[i], "ms_per_scan"), 1000.0 * refine_s / run["scan_count"].get<double>(),
                  1e-6 * Number(rows[i], "ms_per_scan"));
      EXPECT_NEAR(Number(rows[i], "real_time_factor"),
                  run["sequence_duration_s"].get<double>() / refine_s,
                  1e-6 * Number(rows[i], "real_time_factor"));
    } else {
      EXPECT_NEAR(Number(rows[i], "ms_per_scan"), run["per_scan_ms"]["median"].get<double>(),
                  1e-6 * Number(rows[i], "ms_per_scan")) << v;
      EXPECT_NEAR(Number(rows[i], "real_time_factor"), run["real_time_factor"].get<double>(),
                  1e-6 * Number(rows[i], "real_time_factor")) << v;
    }
  }
}

// Deterministic data: every variant is accurate, refine starts from the best
// of the four and does not make it worse.
void CheckAccuracyAndRefineStart(const std::string& out) {
  SCOPED_TRACE("accuracy");
  std::vector<std::string> header;
  const std::vector<CsvRow> rows = ReadCsv(out + "/compare.csv", &header);
  ASSERT_EQ(rows.size(), kVariants.size());
  std::string best;
  double best_ate = INFINITY;
  for (size_t i = 0; i < 4; ++i) {
    const double ate = Number(rows[i], "ate_rmse_m");
    EXPECT_LT(ate, 0.05) << rows[i].at("variant");
    EXPECT_GT(ate, 0.0) << rows[i].at("variant");
    EXPECT_LE(Number(rows[i], "rpe_rmse_m"), ate) << rows[i].at("variant");
    EXPECT_GT(Number(rows[i], "ms_per_scan"), 0.0);
    EXPECT_GT(Number(rows[i], "real_time_factor"), 0.0);
    if (ate < best_ate) best_ate = ate, best = rows[i].at("variant");
    EXPECT_EQ(rows[i].at("init"), "");
  }
  EXPECT_EQ(rows[4].at("init"), best);
  EXPECT_LE(Number(rows[4], "ate_rmse_m"), best_ate + 0.001);
  // refine got the user's --set (2 rounds) and its round lines went to the log.
  const std::string log = ReadFile(out + "/refine/refine.log");
  EXPECT_NE(log.find("round 2/2"), std::string::npos) << log;
  EXPECT_NE(log.find("rvlio refine: " + rows[4].at("scans") + " scans, 2 rounds"),
            std::string::npos) << log;
}

bool StartsWith(const std::string& bytes, const std::string& magic) {
  return bytes.compare(0, magic.size(), magic) == 0;
}

// Valid PNG and PDF files of the three plots and their list in compare.json.
void CheckPlots(const std::string& out) {
  SCOPED_TRACE("plots");
  const std::string plots = out + "/plots/";
  for (const char* kind : {"trajectories", "rv_profile", "compare_bars"}) {
    const std::string png = ReadFile(plots + kind + ".png"), pdf = ReadFile(plots + kind + ".pdf");
    EXPECT_GT(png.size(), 10000u) << kind;
    EXPECT_TRUE(StartsWith(png, "\x89PNG\r\n\x1a\n")) << kind;
    EXPECT_TRUE(StartsWith(pdf, "%PDF-")) << kind;
    EXPECT_NE(pdf.find("%%EOF", pdf.size() > 64 ? pdf.size() - 64 : 0), std::string::npos) << kind;
  }
  std::ifstream in(out + "/compare.json");
  const nlohmann::json summary = nlohmann::json::parse(in, nullptr, false);
  EXPECT_EQ(summary["plots"]["status"], "ok");
  EXPECT_EQ(summary["plots"]["files"].size(), 6u);
}

// refine with 2 rounds instead of 4 keeps the test short and shows that --set
// reaches refine too.
TEST_F(CompareTest, FullCompareWritesTablesEqualToEvalAndPlots) {
  const std::string out = dir_ + "/full";
  const ToolRun full = RunTool(CompareArgs(out, "--set refine.rounds=2"), dir_);
  ASSERT_EQ(full.exit_code, 0) << full.err;
  CheckOutputs(out, full);
  CheckNumbersEqualEval(out, Truth(), dir_);
  CheckAccuracyAndRefineStart(out);
  // report.html (docs/report.md) for the folder, its line on stdout; its
  // contents are checked in test/experiments/report_*_test.cpp.
  EXPECT_TRUE(fs::is_regular_file(out + "/report.html"));
  EXPECT_NE(full.out.find("report: " + out + "/report.html"), std::string::npos) << full.out;
  if (!PlotScriptUsable()) {
    EXPECT_NE(full.out.find("plots skipped: "), std::string::npos) << full.out;
    GTEST_SKIP() << "rvlio_plot.py check failed (no python3 with matplotlib): every other "
                    "output was checked, the plot files were not";
  }
  EXPECT_EQ(full.out.find("plots skipped"), std::string::npos) << full.out;
  CheckPlots(out);
}

// A variant that cannot write its output folder (a file is in the way) is a
// failed row with its exit code; the others go on. Plots are requested but the
// plot script is missing: one "plots skipped" line, still success.
TEST_F(CompareTest, FailedVariantIsRecordedAndTheRestGoOn) {
  const std::string out = dir_ + "/blocked";
  fs::create_directories(out);
  for (const char* v : {"ieskf_rv_on", "smoother_rv_off", "smoother_rv_on"})
    std::ofstream(out + "/" + v) << "in the way\n";
  ScopedEnv env("RVLIO_PLOT_SCRIPT", dir_ + "/no_such_script.py");
  const ToolRun r = RunTool(CompareArgs(out, "--no-refine"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::string> header;
  const std::vector<CsvRow> rows = ReadCsv(out + "/compare.csv", &header);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].at("status"), "ok");
  EXPECT_LT(Number(rows[0], "ate_rmse_m"), 0.05);
  for (size_t i = 1; i < 4; ++i) {
    EXPECT_EQ(rows[i].at("status"), "failed") << rows[i].at("variant");
    EXPECT_EQ(rows[i].at("exit_code"), "2") << rows[i].at("variant");
    EXPECT_TRUE(std::isnan(Number(rows[i], "ate_rmse_m")));
  }
  EXPECT_NE(r.err.find("output folder " + out + "/smoother_rv_on is a regular file, not a folder"),
            std::string::npos) << r.err;
  EXPECT_NE(ReadFile(out + "/compare.md").find("| smoother, RV off | failed (exit 2) |"),
            std::string::npos);
  EXPECT_NE(r.out.find("plots skipped: rvlio_plot.py not found"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(out + "/plots"));
  EXPECT_FALSE(fs::exists(out + "/refine"));
}

// --ref-map: each row's map.pcd, moved into the ground truth's frame by the
// row's trajectory alignment, against the reference cloud. The reference here
// is the map of a refine started from the ground truth (so in its frame);
// three variants are blocked to keep it short.
TEST_F(CompareTest, RefMapAddsMapColumnsInTheGroundTruthFrame) {
  const std::string ref = dir_ + "/ref_run";
  const ToolRun run = RunTool("refine --bag " + Bag() + " --config " + dir_ +
                                  "/data/tunnel.yaml --init " + Truth() +
                                  " --set refine.rounds=1 --out " + ref,
                              dir_);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string out = dir_ + "/with_map";
  fs::create_directories(out);
  for (const char* v : {"ieskf_rv_on", "smoother_rv_off", "smoother_rv_on"})
    std::ofstream(out + "/" + v) << "in the way\n";
  const ToolRun r =
      RunTool(CompareArgs(out, "--no-refine --no-plots --ref-map " + ref + "/map.pcd"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::string> header;
  const std::vector<CsvRow> rows = ReadCsv(out + "/compare.csv", &header);
  ASSERT_EQ(rows.size(), 4u);
  const nlohmann::json j = nlohmann::json::parse(ReadFile(out + "/compare.json"));
  const nlohmann::json& m = j["variants"][0]["map_eval"];
  EXPECT_NEAR(Number(rows[0], "map_rms_m"), m["accuracy"]["rms"].get<double>(), 1e-9);
  EXPECT_NEAR(Number(rows[0], "map_completeness"), m["completeness"].get<double>(), 1e-9);
  EXPECT_LT(Number(rows[0], "map_rms_m"), 0.06);  // two maps of one tunnel, 3 cm range noise
  EXPECT_GT(Number(rows[0], "map_completeness"), 0.5);
  EXPECT_LT(m["outlier_fraction"].get<double>(), 0.2);
  EXPECT_TRUE(std::isnan(Number(rows[1], "map_rms_m")));  // failed row: empty
  EXPECT_EQ(j["ref_map"], ref + "/map.pcd");
  EXPECT_TRUE(m["profile"].is_array());
  EXPECT_NE(ReadFile(out + "/compare.md").find("map RMS [m]"), std::string::npos);
  EXPECT_NE(r.out.find("map RMS"), std::string::npos) << r.out;
}

TEST_F(CompareTest, EveryVariantFailedIsExitOne) {
  const std::string out = dir_ + "/all_blocked";
  fs::create_directories(out);
  for (size_t i = 0; i < 4; ++i) std::ofstream(out + "/" + kVariants[i]) << "in the way\n";
  const ToolRun r = RunTool(CompareArgs(out, "--no-plots --quiet"), dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("rvlio compare: error: every variant failed"), std::string::npos) << r.err;
  std::vector<std::string> header;
  const std::vector<CsvRow> rows = ReadCsv(out + "/compare.csv", &header);
  ASSERT_EQ(rows.size(), 4u);  // no refine without a start
  for (const CsvRow& row : rows) EXPECT_EQ(row.at("status"), "failed");
  EXPECT_EQ(r.out.find("[1/"), std::string::npos) << "--quiet printed step lines:\n" << r.out;
}

TEST_F(CompareTest, BadInputIsOneLineAndExitTwoBeforeAnyRun) {
  const std::string bad = dir_ + "/bad";
  ExpectBadInput("compare --bag " + Bag() + " --out " + bad, "missing required option --gt");
  ExpectBadInput("compare --bag " + Bag() + " --gt " + dir_ + "/missing_gt.tum --out " + bad,
                 dir_ + "/missing_gt.tum");
  std::ofstream(dir_ + "/garbage_gt.tum") << "this is not a trajectory\n1 2 3\n";
  ExpectBadInput("compare --bag " + Bag() + " --gt " + dir_ + "/garbage_gt.tum --out " + bad,
                 "garbage_gt.tum");
  ExpectBadInput("compare --bag " + dir_ + "/missing.bag --gt " + Truth() + " --out " + bad,
                 dir_ + "/missing.bag");
  ExpectBadInput(CompareArgs(bad, "--set rv.epss0=0.5"), "rv.epss0");
  ExpectBadInput(CompareArgs(bad, "--ref-map " + dir_ + "/missing_ref.pcd"),
                 "--ref-map: " + dir_ + "/missing_ref.pcd: cannot open");
}

}  // namespace
}  // namespace rvlio

#include "compare_engine.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli.h"
#include "commands.h"
#include "interrupt.h"
#include "divergence_cli.h"
#include "plot_runner.h"
#include "run_pipeline.h"
#include "time_range_options.h"
#include "rvlio/api.h"
#include "rvlio/common/cpu_time.h"
#include "rvlio/common/text.h"
#include "rvlio/eval/evaluate.h"
#include "rvlio/eval/map_metrics.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/config/config.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/outputs/output_stage.h"
#include "rvlio/outputs/summary_json.h"
#include "rvlio/formats/sensor_bag.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/version.h"

namespace rvlio::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
constexpr const char* kCompare = "compare";
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr const char* kRefine = "refine";

struct Variant {
  std::string name, label;
  std::vector<std::string> overrides;
};

std::vector<Variant> StandardVariants() {
  return {{"ieskf_rv_off", "IESKF, RV off", {"backend=ieskf", "rv.enabled=false"}},
          {"ieskf_rv_on", "IESKF, RV on (RV-LIO)", {"backend=ieskf", "rv.enabled=true"}},
          {"smoother_rv_off", "smoother, RV off", {"backend=smoother", "rv.enabled=false"}},
          {"smoother_rv_on", "smoother, RV on", {"backend=smoother", "rv.enabled=true"}}};
}

// One line of the table. A failed row has exit_code != 0 and no metrics.
struct Row {
  std::string name, label;
  std::string init;  // refine: the variant it started from
  int exit_code = 0;
  std::string error;
  std::optional<EvalResult> eval;
  std::optional<MapEvalResult> map_eval;  // with --ref-map: the run's map.pcd against it
  int scans = 0;
  double ms_per_scan = kNaN;       // run: median CPU ms; refine: wall ms per scan (batch)
  double real_time_factor = kNaN;  // sequence duration / compute time
  double wall_s = 0.0;             // whole step, including reading the bag
  bool interrupted = false;        // a signal stopped it or came before it started
  bool diverged = false;           // the divergence monitor fired: metrics shown, marked

  bool measured() const { return exit_code == 0 && eval.has_value(); }
  bool ok() const { return measured() && !diverged; }
  const char* StatusName() const {
    return interrupted ? "interrupted" : ok() ? "ok" : (measured() ? "diverged" : "failed");
  }
};

class Steps {
 public:
  Steps(const CompareRequest& r)
      : quiet_(r.quiet), next_(r.first_step),
        total_(r.total_steps > 0 ? r.total_steps : CompareSteps(r)) {}
  void Say(const std::string& text) {
    if (quiet_) return;
    std::printf("[%d/%d] %s\n", next_++, total_, text.c_str());
    std::fflush(stdout);
  }
  void Detail(const std::string& text) const {
    if (quiet_) return;
    std::printf("      %s\n", text.c_str());
    std::fflush(stdout);
  }

 private:
  bool quiet_;
  int next_, total_;
};

std::string FixedOrDash(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
  return buf;
}

nlohmann::json Num(double v) {
  if (!std::isfinite(v)) return nullptr;
  return std::strtod(FormatFinite(v, 10).c_str(), nullptr);
}

// What every row is evaluated against.
struct Truth {
  Trajectory trajectory;
  std::vector<Eigen::Vector3d> ref_map;  // empty without --ref-map
};

// ---------------------------------------------------------------------------
// Input checks: everything that would make every run fail, before any run.
// ---------------------------------------------------------------------------

int CheckInputs(const CompareRequest& req, Truth* truth) {
  StatusOr<Configuration> options = LoadConfig(req.config_files, req.overrides);
  if (!options.ok()) return Fail(kCompare, options.status().message());
  for (const Variant& v : StandardVariants()) {
    std::vector<std::string> sets = req.overrides;
    sets.insert(sets.end(), v.overrides.begin(), v.overrides.end());
    if (StatusOr<Configuration> o = LoadConfig(req.config_files, sets); !o.ok())
      return Fail(kCompare, "variant " + v.name + ": " + o.status().message());
  }
  StatusOr<Trajectory> gt = ReadTrajectory(req.gt);
  if (!gt.ok()) return Fail(kCompare, "--gt: " + gt.status().message());
  if (gt->size() < 3)
    return Fail(kCompare, "--gt: " + req.gt + " has " + std::to_string(gt->size()) +
                           " poses; at least 3 are needed to align and evaluate");
  truth->trajectory = std::move(*gt);
  if (!req.ref_map.empty()) {
    StatusOr<PointCloudFile> ref = ReadPointCloud(req.ref_map, PointCloudReadOptions{false});
    if (!ref.ok()) return Fail(kCompare, "--ref-map: " + ref.status().message());
    truth->ref_map = std::move(ref->points);
  }
  ReaderOptions inline_io = options->io;
  inline_io.reader_thread = false;  // only the checks at open: read nothing ahead
  StatusOr<std::unique_ptr<SensorBagReader>> reader =
      OpenSensorStream(req.bag, options->lidar, options->imu, req.window, inline_io);
  if (!reader.ok()) return Fail(kCompare, reader.status().message());
  return 0;
}

// ---------------------------------------------------------------------------
// Runs
// ---------------------------------------------------------------------------

// The run's map.pcd against the reference cloud, as `rvlio eval --map`,
// after moving it into the ground truth's frame by the alignment of the
// run's poses (row->eval->T_ref_est_poses: the estimate's world frame is its
// own, and a small initial tilt moves far walls by centimetres; the ATE's
// Umeyama alignment of positions leaves the roll about a straight path free). A failure is a
// warning and leaves the row's map columns empty.
void EvaluateRowMap(const Truth& truth, const std::string& dir, Row* row) {
  if (truth.ref_map.empty() || !row->eval) return;
  const std::string map_path = dir + "/map.pcd";
  StatusOr<PointCloudFile> map = ReadPointCloud(map_path, PointCloudReadOptions{false});
  if (map.ok())
    for (Eigen::Vector3d& p : map->points) p = row->eval->T_ref_est_poses * p;
  StatusOr<MapEvalResult> m = map.ok() ? EvaluateMap(map->points, truth.ref_map, MapEvalOptions())
                                       : StatusOr<MapEvalResult>(map.status());
  if (!m.ok()) {
    std::fprintf(stderr, "rvlio %s: warning: %s: map evaluation: %s\n", kCompare, row->name.c_str(),
                 m.status().message().c_str());
    return;
  }
  row->map_eval = std::move(*m);
}

void EvaluateRow(const Truth& truth, const std::string& dir, Row* row) {
  StatusOr<Trajectory> est = ReadTum(dir + "/trajectory.tum");
  StatusOr<EvalResult> e = est.ok() ? Evaluate(truth.trajectory, *est, EvalOptions())
                                    : StatusOr<EvalResult>(est.status());
  if (!e.ok()) {
    row->exit_code = cli::ExitCode(e.status().code());
    row->error = "evaluation: " + e.status().message();
    std::fprintf(stderr, "rvlio %s: warning: %s: %s\n", kCompare, row->name.c_str(),
                 row->error.c_str());
    return;
  }
  row->eval = std::move(*e);
  EvaluateRowMap(truth, dir, row);
}

std::string ResultLine(const Row& row) {
  if (row.interrupted) return row.name + " interrupted (its folder holds the scans it finished)";
  if (!row.measured())
    return row.name + " failed (exit " + std::to_string(row.exit_code) + ")" +
           (row.error.empty() ? "" : ": " + row.error);
  char buf[160];
  std::snprintf(buf, sizeof(buf), "ATE %.4f m, %d scans, %.1f s%s", row.eval->ape_m.rmse,
                row.scans, row.wall_s, row.diverged ? ", DIVERGED (summary.json divergence)" : "");
  std::string line = buf;
  if (row.map_eval) {
    std::snprintf(buf, sizeof(buf), "; map RMS %.4f m, completeness %.3f",
                  row.map_eval->accuracy.rmse, row.map_eval->completeness);
    line += buf;
  }
  return line;
}

Row RunVariant(const CompareRequest& req, const Variant& v, const Truth& truth, Steps* steps) {
  steps->Say("rvlio run " + v.name + ": " + v.label);
  Row row;
  row.name = v.name;
  row.label = v.label;
  std::vector<std::string> sets = req.overrides;
  sets.insert(sets.end(), v.overrides.begin(), v.overrides.end());
  RunRequest run;
  run.bag = req.bag;
  run.out_dir = req.out_dir + "/" + v.name;
  run.config_files = req.config_files;
  run.overrides = sets;
  run.quiet = req.quiet;
  run.allow_divergence = true;  // the row is marked instead
  run.window = req.window;
  RunOutcome outcome;
  const auto t0 = Clock::now();
  row.exit_code = RunOdometryOnBag(run, &outcome);
  row.wall_s = SecondsSince(t0);
  row.interrupted = Interrupted() && IsInterruptExit(row.exit_code);
  if (row.exit_code == 0) {
    row.scans = outcome.scans;
    row.ms_per_scan = outcome.median_ms;
    row.real_time_factor = outcome.real_time_factor;
    row.diverged = outcome.diverged;
    EvaluateRow(truth, run.out_dir, &row);
  }
  steps->Detail(ResultLine(row));
  return row;
}

const Row* BestRow(const std::vector<Row>& rows) {
  const Row* best = nullptr;
  for (const Row& r : rows)
    if (r.ok() && (!best || r.eval->ape_m.rmse < best->eval->ape_m.rmse)) best = &r;
  return best;
}

Row RunRefine(const CompareRequest& req, const Row& start, const Truth& truth, Steps* steps) {
  const std::string dir = req.out_dir + "/" + kRefine;
  steps->Say("rvlio refine from " + start.name + " (log: " + dir + "/refine.log)");
  Row row;
  row.name = kRefine;
  row.label = "refine (from " + start.label + ")";
  row.init = start.name;
  RefineRequest refine;
  refine.args.bag = req.bag;
  refine.args.init_path = req.out_dir + "/" + start.name + "/trajectory.tum";
  refine.args.out_dir = dir;
  refine.args.window = req.window;
  refine.config_files = req.config_files;
  refine.overrides = req.overrides;
  refine.allow_divergence = true;  // the row is marked instead
  RefineOutcome outcome;
  const auto t0 = Clock::now();
  {
    std::error_code ec;
    fs::create_directories(dir, ec);  // for the log; refine itself reports a bad folder
    // refine's round lines go to the log instead of between compare's step lines
    std::FILE* log = std::fopen((dir + "/refine.log").c_str(), "w");
    refine.out = log != nullptr ? log : stdout;
    row.exit_code = RefineOnBag(std::move(refine), &outcome);
    if (log != nullptr) std::fclose(log);
  }
  row.wall_s = SecondsSince(t0);
  row.interrupted = Interrupted() && IsInterruptExit(row.exit_code);
  if (row.exit_code == 0) {
    row.scans = outcome.scans;
    if (outcome.scans > 0 && outcome.refine_s > 0)
      row.ms_per_scan = 1000.0 * outcome.refine_s / outcome.scans;
    if (outcome.refine_s > 0) row.real_time_factor = outcome.sequence_duration_s / outcome.refine_s;
    row.diverged = outcome.diverged;
    EvaluateRow(truth, dir, &row);
  }
  steps->Detail(ResultLine(row));
  return row;
}

// ---------------------------------------------------------------------------
// Tables
// ---------------------------------------------------------------------------

const char* kCsvHeader =
    "variant,label,status,exit_code,init,scans,ate_rmse_m,rpe_rmse_m,axis_max_m,end_point_m,"
    "ms_per_scan,real_time_factor\n";

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

// The map columns (with --ref-map): accuracy RMS and completeness, or empty.
std::string MapCsvFields(const Row& r) {
  if (!r.map_eval) return ",,";
  return "," + FormatFinite(r.map_eval->accuracy.rmse, 10) + "," +
         FormatFinite(r.map_eval->completeness, 10);
}

std::string CsvText(const std::vector<Row>& rows, bool with_map) {
  std::ostringstream os;
  std::string header = kCsvHeader;
  if (with_map) header.insert(header.size() - 1, ",map_rms_m,map_completeness");
  os << header;
  for (const Row& r : rows) {
    os << r.name << "," << CsvField(r.label) << "," << r.StatusName() << ","
       << r.exit_code << "," << r.init << "," << r.scans;
    if (r.measured()) {
      os << "," << FormatFinite(r.eval->ape_m.rmse, 10) << ","
         << FormatFinite(r.eval->rpe.trans_m.rmse, 10) << ","
         << FormatFinite(r.eval->along_axis.max_abs_m, 10) << ","
         << FormatFinite(r.eval->end_point_error_m, 10) << "," << FormatFinite(r.ms_per_scan, 10)
         << "," << FormatFinite(r.real_time_factor, 10);
    } else {
      os << ",,,,,,";
    }
    if (with_map) os << (r.measured() ? MapCsvFields(r) : ",,");
    os << "\n";
  }
  return os.str();
}

std::string AlignName(const std::vector<Row>& rows) {
  for (const Row& r : rows)
    if (r.measured()) return AlignModeName(r.eval->align);
  return "se3";
}

std::string MarkdownText(const CompareRequest& req, const std::vector<Row>& rows) {
  std::ostringstream os;
  const bool with_map = !req.ref_map.empty();
  os << "| variant | ATE [m] | RPE [m] | along-axis max [m] | end-point [m] | ms/scan | "
        "real-time factor |"
     << (with_map ? " map RMS [m] | completeness |" : "") << "\n|---|---|---|---|---|---|---|"
     << (with_map ? "---|---|" : "") << "\n";
  for (const Row& r : rows) {
    os << "| " << r.label << (r.diverged ? " (**diverged**)" : "") << " | ";
    if (r.interrupted) {
      os << "interrupted | | | | | |\n";
      continue;
    }
    if (!r.measured()) {
      os << "failed (exit " << r.exit_code << ") | | | | | |\n";
      continue;
    }
    os << FixedOrDash(r.eval->ape_m.rmse, 4) << " | " << FixedOrDash(r.eval->rpe.trans_m.rmse, 4) << " | "
       << FixedOrDash(r.eval->along_axis.max_abs_m, 4) << " | " << FixedOrDash(r.eval->end_point_error_m, 4)
       << " | " << FixedOrDash(r.ms_per_scan, 2) << (r.name == kRefine ? " (wall)" : "") << " | "
       << FixedOrDash(r.real_time_factor, 1) << "x |";
    if (with_map)
      os << " " << (r.map_eval ? FixedOrDash(r.map_eval->accuracy.rmse, 4) : "-") << " | "
         << (r.map_eval ? FixedOrDash(r.map_eval->completeness, 3) : "-") << " |";
    os << "\n";
  }
  os << "\nBag `" << req.bag << "`, ground truth `" << req.gt << "`. ATE: translation RMSE after "
     << AlignName(rows)
     << " alignment; RPE: 1-frame translation RMSE; along-axis max: largest error along the "
        "principal axis of the ground truth; end-point: error of the last pose. ms/scan: median "
        "CPU time per scan of the odometry (refine: wall time of the batch solve divided by the "
        "scans); real-time factor: sequence duration / that time.";
  if (with_map)
    os << " Map RMS: point-to-plane RMS distance of the run's map.pcd, moved into the ground "
       << "truth's frame by the ATE alignment, to the reference cloud `" << req.ref_map
       << "` over the map points within 0.1 m of it; completeness: the fraction of reference "
       << "points with a map point within 0.1 m (`rvlio eval --map`).";
  os << "\n";
  return os.str();
}

void PrintTable(const std::vector<Row>& rows, bool with_map) {
  std::printf("\n  %-30s %9s %9s %12s %9s %9s %8s%s\n", "variant", "ATE [m]", "RPE [m]",
              "axis max [m]", "end [m]", "ms/scan", "speed",
              with_map ? "  map RMS [m]  complete" : "");
  for (const Row& r : rows) {
    if (r.interrupted) {
      std::printf("  %-30s interrupted\n", r.label.c_str());
      continue;
    }
    if (!r.measured()) {
      std::printf("  %-30s failed (exit %d)\n", r.label.c_str(), r.exit_code);
      continue;
    }
    std::string map_cols;
    if (with_map) {
      char buf[64];
      if (r.map_eval)
        std::snprintf(buf, sizeof(buf), "  %11.4f  %8.3f", r.map_eval->accuracy.rmse,
                      r.map_eval->completeness);
      else
        std::snprintf(buf, sizeof(buf), "  %11s  %8s", "-", "-");
      map_cols = buf;
    }
    std::printf("  %-30s %9.4f %9.4f %12.4f %9.4f %9.2f %7.1fx%s%s\n", r.label.c_str(),
                r.eval->ape_m.rmse, r.eval->rpe.trans_m.rmse, r.eval->along_axis.max_abs_m,
                r.eval->end_point_error_m, r.ms_per_scan, r.real_time_factor, map_cols.c_str(),
                r.diverged ? "  DIVERGED" : "");
  }
  std::printf("\n  ATE: RMSE after %s alignment; RPE: 1-frame translation RMSE; axis max: largest\n"
              "  error along the tunnel axis; end: end-point error. ms/scan: median CPU time per\n"
              "  scan (refine: wall time of the batch solve per scan); speed: real-time factor.\n",
              AlignName(rows).c_str());
  if (with_map)
    std::printf("  map RMS: point-to-plane RMS of map.pcd (in the ground truth's frame by the ATE\n"
                "  alignment) to the reference cloud (points within 0.1 m); complete: reference\n"
                "  points with a map point within 0.1 m.\n");
}

nlohmann::json StatsJson(const ErrorStats& s) {
  return {{"rmse", Num(s.rmse)}, {"mean", Num(s.mean)}, {"median", Num(s.median)},
          {"std", Num(s.std)},   {"min", Num(s.min)},   {"max", Num(s.max)}};
}

nlohmann::json RowJson(const CompareRequest& req, const Row& r,
                       const std::vector<std::string>& overrides) {
  nlohmann::json j = {{"variant", r.name},
                      {"label", r.label},
                      {"status", r.StatusName()},
                      {"diverged", r.diverged},
                      {"exit_code", r.exit_code},
                      {"dir", req.out_dir + "/" + r.name},
                      {"overrides", overrides},
                      {"wall_s", Num(r.wall_s)}};
  if (!r.init.empty()) j["init"] = r.init;
  if (!r.error.empty()) j["error"] = r.error;
  if (!r.measured()) return j;
  const EvalResult& e = *r.eval;
  j["scans"] = r.scans;
  j["ate_rmse_m"] = Num(e.ape_m.rmse);
  j["rpe_rmse_m"] = Num(e.rpe.trans_m.rmse);
  j["axis_max_m"] = Num(e.along_axis.max_abs_m);
  j["end_point_m"] = Num(e.end_point_error_m);
  j["ms_per_scan"] = Num(r.ms_per_scan);
  j["ms_per_scan_kind"] = r.name == kRefine ? "wall, batch solve / scans" : "CPU, median";
  j["real_time_factor"] = Num(r.real_time_factor);
  if (r.map_eval) {
    j["map_rms_m"] = Num(r.map_eval->accuracy.rmse);
    j["map_completeness"] = Num(r.map_eval->completeness);
    j["map_eval"] = MapEvalJson(*r.map_eval);
  }
  j["eval"] = {{"matched", e.matched},
               {"align", AlignModeName(e.align)},
               {"ape", StatsJson(e.ape_m)},
               {"ape_rot_deg", StatsJson(e.ape_rot_deg)},
               {"rpe", StatsJson(e.rpe.trans_m)},
               {"rpe_rot_deg", StatsJson(e.rpe.rot_deg)},
               {"end_point_error", Num(e.end_point_error_m)},
               {"along_axis",
                {{"rmse", Num(e.along_axis.rmse_m)}, {"max", Num(e.along_axis.max_abs_m)}}},
               {"warnings", e.warnings}};
  return j;
}

// ---------------------------------------------------------------------------
// Plots
// ---------------------------------------------------------------------------

struct PlotReport {
  std::string status = "not requested";  // "ok", "skipped", "partial"
  std::string message;
  std::vector<std::string> files;
};

const Row* FindRow(const std::vector<Row>& rows, const std::string& name) {
  for (const Row& r : rows)
    if (r.name == name && r.ok()) return &r;
  return nullptr;
}

// Draws OUT/plots/{trajectories,rv_profile,compare_bars}.{png,pdf}.
PlotReport DrawPlots(const CompareRequest& req, const std::vector<Row>& rows) {
  PlotReport report;
  const std::string dir = req.out_dir + "/plots/";
  std::vector<std::pair<std::string, std::vector<std::string>>> jobs;
  std::vector<std::string> traj = {"trajectories", "--gt", req.gt, "--align", "se3", "--out", dir};
  for (const Row& r : rows)
    if (r.ok()) traj.insert(traj.end(), {"--run", r.name + "=" + req.out_dir + "/" + r.name});
  jobs.push_back({"trajectories", traj});
  if (FindRow(rows, "ieskf_rv_on"))
    jobs.push_back({"rv_profile", {"rv-profile", "--run", req.out_dir + "/ieskf_rv_on", "--gt",
                                   req.gt, "--out", dir}});
  std::vector<std::string> bars = {"compare-bars", "--table", req.out_dir + "/compare.csv",
                                   "--out", dir};
  if (!req.ref_map.empty())
    for (const char* metric : {"ate_rmse_m", "rpe_rmse_m", "axis_max_m", "map_rms_m",
                               "map_completeness"})
      bars.insert(bars.end(), {"--metric", metric});
  jobs.push_back({"compare_bars", bars});
  std::vector<std::string> failures;
  for (const auto& [kind, args] : jobs) {
    const PlotResult p = RunPlotScript(args);
    if (!p.ran) {
      report.status = "skipped";
      report.message = p.message;
      return report;
    }
    if (!p.ok) {
      failures.push_back(kind + ": " + p.message);
      continue;
    }
    for (const char* ext : {".png", ".pdf"}) report.files.push_back(dir + kind + ext);
  }
  report.status = failures.empty() ? "ok" : "partial";
  for (const auto& f : failures) report.message += (report.message.empty() ? "" : "; ") + f;
  return report;
}

void PrintPlotReport(const CompareRequest& req, const PlotReport& plots) {
  if (plots.status == "skipped") {
    std::printf("  plots skipped: %s\n", plots.message.c_str());
    return;
  }
  if (plots.status == "partial")
    std::fprintf(stderr, "rvlio %s: warning: some plots failed: %s\n", kCompare,
                 plots.message.c_str());
  if (plots.files.empty()) return;
  std::printf("  plots:  %s/plots/ (", req.out_dir.c_str());
  for (size_t i = 0; i < plots.files.size(); i += 2)
    std::printf("%s%s", i ? ", " : "", fs::path(plots.files[i]).stem().c_str());
  std::printf("; .png and .pdf)\n");
}

Status WriteJson(const CompareRequest& req, const std::vector<Row>& rows,
                 const PlotReport& plots) {
  nlohmann::json j;
  j["version"] = RVLIO_VERSION;
  j["command"] = kCompare;
  j["bag"] = req.bag;
  j["gt"] = req.gt;
  if (!req.ref_map.empty()) j["ref_map"] = req.ref_map;
  j["config"] = req.config_files;
  j["set"] = req.overrides;
  j["align"] = AlignName(rows);
  j["variants"] = nlohmann::json::array();
  const std::vector<Variant> variants = StandardVariants();
  for (const Row& r : rows) {
    std::vector<std::string> overrides;
    for (const Variant& v : variants)
      if (v.name == r.name) overrides = v.overrides;
    j["variants"].push_back(RowJson(req, r, overrides));
  }
  j["plots"] = {{"status", plots.status}, {"message", plots.message}, {"files", plots.files}};
  return WriteFileAtomically(req.out_dir + "/compare.json", JsonText(j) + "\n");
}

// A row for a step a signal came before.
Row NotRun(const std::string& name, const std::string& label) {
  Row row;
  row.name = name;
  row.label = label;
  row.exit_code = InterruptExitCode();
  row.interrupted = true;
  return row;
}

// compare.json without plots, and the one line; returns 130 / 143.
int ReportInterrupt(const CompareRequest& req, const std::vector<Row>& rows) {
  PlotReport plots;
  plots.status = "skipped";
  plots.message = "interrupted";
  if (Status s = WriteJson(req, rows, plots); !s.ok()) return Fail(kCompare, s.message(), 1);
  int finished = 0;
  for (const Row& r : rows) finished += r.interrupted ? 0 : 1;
  std::fprintf(stderr, "rvlio compare: interrupted by %s: %d of %zu steps finished; wrote "
               "compare.{csv,md,json} (the rest marked interrupted) to %s\n",
               InterruptSignalName().c_str(), finished, rows.size(), req.out_dir.c_str());
  return InterruptExitCode();
}

}  // namespace

int CompareSteps(const CompareRequest& request) {
  return static_cast<int>(StandardVariants().size()) + (request.refine ? 1 : 0);
}

int RunCompare(const CompareRequest& req) {
  InterruptScope interrupt_scope;  // SIGINT/SIGTERM: stop the running variant, tabulate, 130/143
  Truth truth;
  if (int rc = CheckInputs(req, &truth); rc != 0) return rc;
  OutputFolder out_folder(req.out_dir);  // removed again when it stays empty
  if (Status s = out_folder.Prepare(); !s.ok()) return Fail(kCompare, s);
  Steps steps(req);
  std::vector<Row> rows;
  for (const Variant& v : StandardVariants())
    rows.push_back(Interrupted() ? NotRun(v.name, v.label) : RunVariant(req, v, truth, &steps));
  if (const Row* best = BestRow(rows); req.refine && Interrupted()) {
    rows.push_back(NotRun(kRefine, "refine"));
  } else if (req.refine && best != nullptr) {
    const Row start = *best;  // rows grows below
    rows.push_back(RunRefine(req, start, truth, &steps));
  }
  const bool any_ok = BestRow(rows) != nullptr;
  const bool with_map = !req.ref_map.empty();
  for (const auto& [file, text] :
       {std::pair<std::string, std::string>{"compare.csv", CsvText(rows, with_map)},
        {"compare.md", MarkdownText(req, rows)}}) {
    if (Status s = WriteFileAtomically(req.out_dir + "/" + file, text); !s.ok())
      return Fail(kCompare, s.message(), 1);
  }
  PrintTable(rows, with_map);
  PlotReport plots;
  if (Interrupted()) return ReportInterrupt(req, rows);
  if (req.plots && any_ok) plots = DrawPlots(req, rows);
  if (Status s = WriteJson(req, rows, plots); !s.ok()) return Fail(kCompare, s.message(), 1);
  std::printf("\n  tables: %s/compare.{csv,md,json}; runs: %s/<variant>/\n", req.out_dir.c_str(),
              req.out_dir.c_str());
  if (req.plots) PrintPlotReport(req, plots);
  WriteFolderReport(kCompare, req.out_dir, req.quiet);
  int diverged = 0;
  for (const Row& r : rows) diverged += r.diverged ? 1 : 0;
  if (!any_ok && diverged > 0)
    return Fail(kCompare, "every variant failed or diverged (see the table and each run's summary.json "
                "divergence)", kExitDiverged);
  if (!any_ok) return Fail(kCompare, "every variant failed (see the table)", 1);
  if (diverged > 0)
    std::fprintf(stderr, "rvlio %s: warning: %d run(s) diverged, marked in the table\n", kCompare,
                 diverged);
  return 0;
}

}  // namespace rvlio::cli

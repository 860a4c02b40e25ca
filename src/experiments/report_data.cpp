#include "rvlio/experiments/report_data.h"

#include "report_model.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>

#include "rvlio/eval/evaluate.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/outputs/run_outputs.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/formats/control_file.h"
#include "rvlio/math/local_origin.h"
#include "rvlio/outputs/summary_json.h"
#include "rvlio/version.h"

namespace rvlio::experiments::report {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr const char* kDeviationField = "deviation_m";
constexpr const char* kIntensityField = "intensity";

// The columns of scans.csv the page plots when present: the RV activity, the
// health of the estimate, and the reference-map localization columns.
const std::vector<std::string>& PlottedScanColumns() {
  static const std::vector<std::string> kColumns = {
      "rv_active",        "scv",           "coplanar_fraction", "localizability",
      "constraints",      "nis",           "residual_median_m", "residual_rms_m",
      "diverged",         "map_overlap",   "localized",         "ms"};
  return kColumns;
}

bool IsFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

json ReadJson(const fs::path& path) { return ReadJsonFile(path.string()); }

// A path recorded in a folder's JSON (relative to the directory the command
// ran in): as written when it exists, else re-rooted at `dir` when it starts
// with the output folder the command was given (`recorded_out`).
std::string Resolve(const std::string& recorded, const std::string& recorded_out,
                    const std::string& dir) {
  if (recorded.empty() || IsFile(recorded) || fs::is_directory(recorded)) return recorded;
  const fs::path rel = fs::path(recorded).lexically_relative(recorded_out);
  if (!recorded_out.empty() && !rel.empty() && *rel.begin() != "..")
    return (fs::path(dir) / rel).lexically_normal().string();
  return recorded;
}

float ToFloat(double v) { return static_cast<float>(v); }

// What the page's float32 arrays are relative to: times to t0_s and
// positions to a local origin (math/local_origin.h), both taken from the
// ground truth, else from the first run's trajectory. A float32 keeps only
// decimetres of a national grid's coordinates (UTM northings of 5e6 m) and
// hundredths of a second of a Unix time stamp.
struct PageFrame {
  double t0_s = 0.0;
  LocalOrigin origin;
};

PageFrame FrameOf(const Trajectory& t) {
  return {NsToSeconds(t.front().t_ns), ChooseLocalOrigin(t)};
}

// control.csv of `refine --control` (docs/control.md): its table, numbers as
// numbers, and the given positions (x, y relative to the page's origin) for
// the top view. Null when it cannot be read (a note says so).
json ControlJson(const std::string& path, const LocalOrigin& origin,
                 std::vector<std::string>* notes) {
  std::ifstream in(path, std::ios::binary);
  StatusOr<std::vector<ControlResidual>> rows =
      ParseControlCsv(std::string(std::istreambuf_iterator<char>(in), {}), path);
  if (!rows.ok()) {
    notes->push_back("control points not shown: " + rows.status().message());
    return nullptr;
  }
  json table = {{"columns", {"name", "role", "kind", "dx_m", "dy_m", "dz_m", "d3d_m", "sigma_m",
                             "x", "y", "z"}},
                {"rows", json::array()}};
  std::vector<float> xy;
  json names = json::array(), roles = json::array();
  for (const ControlResidual& r : *rows) {
    const Eigen::Vector3d d = r.Residual();
    json row = {r.row.name, ControlRoleName(r.row.role), r.kind};
    for (int a = 0; a < 3; ++a) row.push_back(r.estimated ? json(d[a]) : json(nullptr));
    row.push_back(r.estimated ? json(d.norm()) : json(nullptr));
    row.push_back(r.sigma_m);
    for (int a = 0; a < 3; ++a) row.push_back(r.row.p_survey[a]);
    table["rows"].push_back(row);
    const Eigen::Vector3d p = origin.ToLocal(r.row.p_survey);
    xy.push_back(ToFloat(p.x()));
    xy.push_back(ToFloat(p.y()));
    names.push_back(r.row.name);
    roles.push_back(ControlRoleName(r.row.role));
  }
  table["marks"] = {{"xy", ReportArray(xy)}, {"names", names}, {"roles", roles}};
  table["caption"] = "From " + path +
                     ": estimated minus given survey coordinates [m]; a check point's residual "
                     "is the delivered accuracy (it never entered the solve).";
  return table;
}

// ---------------------------------------------------------------------------
// Runs
// ---------------------------------------------------------------------------

struct RunEntry {
  std::string name, label, status, dir;
};

// The estimate aligned to the ground truth and its along-axis error at the
// matched poses, both as `rvlio eval` computes them (rvlio/eval/evaluate.h).
struct Aligned {
  Trajectory est_in_ref;
  std::vector<float> axis_t, axis_err_m;
};

std::optional<Aligned> AlignToTruth(const Trajectory& truth, const Trajectory& est, double t0_s,
                                    std::vector<std::string>* notes, const std::string& name) {
  StatusOr<EvalResult> e = Evaluate(truth, est, EvalOptions());
  if (!e.ok()) {
    notes->push_back(name + ": not aligned to the ground truth (" + e.status().message() + ")");
    return std::nullopt;
  }
  Aligned out;
  out.est_in_ref = e->T_ref_est.Apply(est);
  const std::vector<size_t>& ref_index = e->association.ref_index;
  for (size_t k = 0; k < ref_index.size(); ++k) {
    out.axis_t.push_back(ToFloat(NsToSeconds(truth[ref_index[k]].t_ns) - t0_s));
    out.axis_err_m.push_back(ToFloat(e->along_axis.errors_m[k]));
  }
  return out;
}

json TrajectoryJson(const Trajectory& t, const PageFrame& frame) {
  std::vector<float> times, xyz;
  for (const StampedPose& p : t) {
    times.push_back(ToFloat(NsToSeconds(p.t_ns) - frame.t0_s));
    const Eigen::Vector3d p_local = frame.origin.ToLocal(p.p_world_imu);
    for (int i = 0; i < 3; ++i) xyz.push_back(ToFloat(p_local[i]));
  }
  return {{"t", ReportArray(times)}, {"xyz", ReportArray(xyz)}, {"n", t.size()}};
}

json ScansJson(const ScanTable& scans, double t0_s) {
  const std::vector<double>* t = scans.Find("t");
  if (t == nullptr) return nullptr;
  std::vector<float> times;
  for (double v : *t) times.push_back(ToFloat(v - t0_s));
  json columns = json::array();  // in PlottedScanColumns' order
  for (const std::string& name : PlottedScanColumns()) {
    const std::vector<double>* c = scans.Find(name);
    if (c == nullptr) continue;
    std::vector<float> values;
    for (double v : *c) values.push_back(ToFloat(v));
    columns.push_back({{"name", name}, {"values", ReportArray(values)}});
  }
  return {{"t", ReportArray(times)}, {"n", times.size()}, {"columns", columns}};
}

json RunJson(const RunEntry& run, const Trajectory* truth, const PageFrame& frame,
             std::vector<std::string>* notes) {
  const double t0_s = frame.t0_s;
  json j = {{"name", run.name}, {"label", run.label}, {"status", run.status}};
  StatusOr<Trajectory> est = ReadTrajectory(run.dir + "/trajectory.tum");
  if (!est.ok()) {
    notes->push_back(run.name + ": " + est.status().message());
    return j;
  }
  std::optional<Aligned> aligned;
  if (truth != nullptr) aligned = AlignToTruth(*truth, *est, t0_s, notes, run.name);
  j["trajectory"] = TrajectoryJson(aligned ? aligned->est_in_ref : *est, frame);
  j["aligned"] = aligned.has_value();
  if (aligned)
    j["axis_error"] = {{"t", ReportArray(aligned->axis_t)},
                       {"err", ReportArray(aligned->axis_err_m)},
                       {"n", aligned->axis_t.size()}};
  if (!IsFile(run.dir + "/scans.csv")) return j;  // refine writes none
  if (StatusOr<ScanTable> scans = ReadScanTable(run.dir + "/scans.csv"); scans.ok())
    j["scans"] = ScansJson(*scans, t0_s);
  else
    notes->push_back(run.name + ": " + scans.status().message());
  return j;
}

// ---------------------------------------------------------------------------
// The map
// ---------------------------------------------------------------------------

json CloudJson(const std::string& run_name, const std::string& map_path, const LocalOrigin& origin,
               const ReportOptions& options, std::vector<std::string>* notes) {
  PointCloudReadOptions read_options;
  read_options.allow_empty = true;  // a run over too few scans writes an empty map
  StatusOr<PointCloudFile> cloud = ReadPointCloud(map_path, read_options);
  if (!cloud.ok()) {
    notes->push_back("map: " + cloud.status().message());
    return nullptr;
  }
  const PointCloudField* deviation_field = cloud->Field(kDeviationField);
  const std::vector<float>* deviation = deviation_field ? &deviation_field->values : nullptr;
  const PointCloudField* intensity_field = cloud->Field(kIntensityField);
  const size_t n = cloud->points.size();
  const size_t stride = ThinningStride(n, options.max_points);
  std::vector<float> xyz, value, intensity;
  for (size_t i = 0; i < n; i += stride) {
    const Eigen::Vector3d p = origin.ToLocal(cloud->points[i]);
    if (!p.allFinite()) continue;
    for (int k = 0; k < 3; ++k) xyz.push_back(ToFloat(p[k]));
    value.push_back(deviation ? (*deviation)[i] : ToFloat(p.z()));
    if (intensity_field != nullptr) intensity.push_back(intensity_field->values[i]);
  }
  // The page colours by `field` first; height (from xyz) and these fields
  // are offered beside it.
  json others = json::object();
  if (intensity_field != nullptr) others[kIntensityField] = ReportArray(intensity);
  return {{"run", run_name},
          {"file", map_path},
          {"field", deviation ? kDeviationField : "z"},
          {"total", n},
          {"shown", value.size()},
          {"stride", stride},
          {"xyz", ReportArray(xyz)},
          {"value", ReportArray(value)},
          {"other_fields", others}};
}

// ---------------------------------------------------------------------------
// Folder kinds
// ---------------------------------------------------------------------------

struct Collected {
  std::string title, gt;
  std::vector<RunEntry> runs;
  std::string map_run;  // whose map.pcd is shown
  json table;
  std::vector<std::string> notes;
};

json TableJson(const std::vector<json>& rows, const std::vector<std::string>& leading,
               const std::vector<std::string>& skip) {
  const std::vector<std::string> columns = MetricColumns(rows, leading, skip);
  json out_rows = json::array();
  for (const json& r : rows) {
    json cells = json::array();
    for (const std::string& c : columns) cells.push_back(ColumnValue(r, c));
    out_rows.push_back(cells);
  }
  return {{"columns", columns}, {"rows", out_rows}};
}

double Metric(const json& row, const std::string& column) {
  const json v = ColumnValue(row, column);
  return v.is_number() ? v.get<double>() : kNaN;
}

// The run with the smallest finite `metric` among `candidates` (the first
// when none has one).
std::string BestRun(const std::vector<std::pair<std::string, double>>& candidates) {
  std::string best = candidates.empty() ? "" : candidates.front().first;
  double best_v = std::numeric_limits<double>::infinity();
  for (const auto& [name, v] : candidates)
    if (std::isfinite(v) && v < best_v) {
      best_v = v;
      best = name;
    }
  return best;
}

StatusOr<Collected> CollectCompare(const std::string& dir, FolderKind kind) {
  const json j = ReadJson(fs::path(dir) / "compare.json");
  if (!j.is_object() || !j.contains("variants") || !j["variants"].is_array())
    return Status::InvalidInput(dir + "/compare.json: unreadable or without variants");
  Collected c;
  c.title = std::string("rvlio ") + (kind == FolderKind::kDemo ? "demo" : "compare") + ": " + dir;
  std::string recorded_out;
  std::vector<json> rows;
  std::vector<std::pair<std::string, double>> ranked;
  for (const json& v : j["variants"]) {
    if (!v.is_object()) continue;
    rows.push_back(v);
    const std::string name = v.value("variant", "");
    const std::string recorded_dir = v.value("dir", "");
    if (recorded_out.empty() && recorded_dir.size() > name.size() + 1)
      recorded_out = recorded_dir.substr(0, recorded_dir.size() - name.size() - 1);
    const std::string status = v.value("status", "");
    if (status != "ok" && status != "diverged") continue;
    c.runs.push_back({name, v.value("label", name), status, (fs::path(dir) / name).string()});
    if (status == "ok") ranked.emplace_back(name, Metric(v, "ate_rmse_m"));
  }
  c.gt = Resolve(j.value("gt", ""), recorded_out, dir);
  // compare's own metrics first, in its table's order; any other column after.
  c.table = TableJson(rows,
                      {"label", "status", "ate_rmse_m", "rpe_rmse_m", "axis_max_m", "end_point_m",
                       "ms_per_scan", "real_time_factor"},
                      {"eval", "overrides"});
  // refine is what compare recommends when it ran cleanly; else the best ATE.
  for (const RunEntry& r : c.runs)
    if (r.name == "refine" && r.status == "ok") c.map_run = r.name;
  if (c.map_run.empty()) c.map_run = BestRun(ranked);
  return c;
}

StatusOr<Collected> CollectAblate(const std::string& dir, const ReportOptions& options) {
  const json plan = ReadJson(fs::path(dir) / "plan.json");
  if (!plan.is_object() || !plan.contains("cells") || !plan["cells"].is_array())
    return Status::InvalidInput(dir + "/plan.json: unreadable or without cells");
  Collected c;
  c.title = "rvlio ablate: " + dir;
  const std::string recorded_out = plan.value("out", "");
  std::vector<json> rows;
  std::vector<std::pair<std::string, double>> ranked;
  std::string shown_data;  // the trajectories drawn: those of the first sequence/seed that ran
  for (const json& cell : plan["cells"]) {
    const std::string id = cell.value("id", "");
    const fs::path cell_dir = fs::path(dir) / "cells" / id;
    json record = ReadJson(cell_dir / "cell.json");
    if (!record.is_object()) record = {{"id", id}, {"status", "missing"}};
    json row = {{"id", id}, {"sequence", cell.value("sequence", "")},
                {"label", cell.value("label", "")}, {"seed", cell.value("seed", json(nullptr))},
                {"status", record.value("status", "missing")}};
    if (record.contains("metrics")) row["metrics"] = record["metrics"];
    rows.push_back(row);
    const std::string status = row["status"];
    if (status != "done" && status != "diverged") continue;
    const std::string data = cell.contains("data") && cell["data"].is_string()
                                 ? cell["data"].get<std::string>()
                                 : cell.value("sequence", "");
    if (shown_data.empty()) {
      shown_data = data;
      for (const json& d : plan.value("data", json::array()))
        if (d.value("id", "") == data) c.gt = Resolve(d.value("gt", ""), recorded_out, dir);
    }
    if (data != shown_data) continue;
    if (c.runs.size() >= options.max_runs) {
      c.notes.push_back("trajectories: only the first " + std::to_string(options.max_runs) +
                        " cells of " + shown_data + " are drawn");
      continue;
    }
    c.runs.push_back({id, cell.value("label", id), status, (cell_dir / "run").string()});
    if (status == "done") ranked.emplace_back(id, Metric(row, "metrics.ate_rmse"));
  }
  if (!shown_data.empty()) c.notes.push_back("trajectories and the map: sequence " + shown_data);
  c.table = TableJson(rows, {"sequence", "label", "seed", "status"}, {});
  c.map_run = BestRun(ranked);
  return c;
}

StatusOr<Collected> CollectRun(const std::string& dir, const ReportOptions& options) {
  const json summary = ReadJson(fs::path(dir) / "summary.json");
  if (!summary.is_object()) return Status::InvalidInput(dir + "/summary.json: unreadable");
  Collected c;
  c.title = "rvlio run: " + dir;
  const std::string name = fs::path(dir).lexically_normal().filename().string();
  c.runs.push_back({name.empty() ? "run" : name, name, "ok", dir});
  c.map_run = c.runs.front().name;
  c.gt = options.gt;
  json row = {{"run", name}};
  for (const auto& [key, value] : summary.items())
    if (key != "config" && key != "extrinsic") row[key] = value;
  c.table = TableJson({row}, {"run"}, {"config", "extrinsic"});
  return c;
}

StatusOr<Collected> Collect(const std::string& dir, FolderKind kind, const ReportOptions& o) {
  switch (kind) {
    case FolderKind::kCompare:
    case FolderKind::kDemo:
      return CollectCompare(dir, kind);
    case FolderKind::kAblate:
      return CollectAblate(dir, o);
    case FolderKind::kRun:
      return CollectRun(dir, o);
  }
  return Status::InvalidInput(dir + ": unknown folder kind");
}

// Adds the eval metrics of a run folder against --gt to its one table row.
void AddRunEvalColumns(const Trajectory& truth, const std::string& dir, json* table) {
  StatusOr<Trajectory> est = ReadTrajectory(dir + "/trajectory.tum");
  if (!est.ok()) return;
  StatusOr<EvalResult> e = Evaluate(truth, *est, EvalOptions());
  if (!e.ok()) return;
  const std::vector<std::pair<std::string, double>> metrics = {
      {"ate_rmse_m", e->ape_m.rmse},
      {"rpe_rmse_m", e->rpe.trans_m.rmse},
      {"axis_max_m", e->along_axis.max_abs_m},
      {"end_point_m", e->end_point_error_m}};
  json& columns = (*table)["columns"];
  json& row = (*table)["rows"][0];
  for (size_t i = 0; i < metrics.size(); ++i) {
    columns.insert(columns.begin() + 1 + static_cast<std::ptrdiff_t>(i), metrics[i].first);
    row.insert(row.begin() + 1 + static_cast<std::ptrdiff_t>(i), metrics[i].second);
  }
}

}  // namespace

const char* FolderKindName(FolderKind kind) {
  switch (kind) {
    case FolderKind::kCompare: return "compare";
    case FolderKind::kDemo: return "demo";
    case FolderKind::kAblate: return "ablate";
    case FolderKind::kRun: return "run";
  }
  return "?";
}

StatusOr<FolderKind> DetectFolderKind(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return Status::InvalidInput(dir + ": no such folder");
  const fs::path d(dir);
  if (IsFile(d / "compare.json"))
    return fs::is_directory(d / "data", ec) ? FolderKind::kDemo : FolderKind::kCompare;
  if (IsFile(d / "plan.json") && fs::is_directory(d / "cells", ec)) return FolderKind::kAblate;
  if (IsFile(d / "summary.json") && IsFile(d / "trajectory.tum")) return FolderKind::kRun;
  return Status::InvalidInput(dir + ": nothing to report (no compare.json, plan.json with cells/, "
                              "or summary.json with trajectory.tum)");
}

std::string ReportArray(const std::vector<float>& values) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string bytes(values.size() * sizeof(float), '\0');
  for (size_t i = 0; i < values.size(); ++i) {  // little-endian whatever the host
    uint32_t u = 0;
    std::memcpy(&u, &values[i], sizeof(u));
    for (int b = 0; b < 4; ++b) bytes[4 * i + b] = static_cast<char>((u >> (8 * b)) & 0xff);
  }
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t left = std::min<size_t>(3, bytes.size() - i);
    uint32_t chunk = 0;
    for (size_t k = 0; k < 3; ++k)
      chunk = (chunk << 8) | (k < left ? static_cast<unsigned char>(bytes[i + k]) : 0u);
    for (size_t k = 0; k < 4; ++k)
      out += k <= left ? kAlphabet[(chunk >> (18 - 6 * k)) & 0x3f] : '=';
  }
  return out;
}

size_t ThinningStride(size_t points, size_t max_points) {
  if (max_points == 0 || points <= max_points) return 1;
  return (points + max_points - 1) / max_points;
}

std::vector<std::string> MetricColumns(const std::vector<json>& rows,
                                       const std::vector<std::string>& leading,
                                       const std::vector<std::string>& skip) {
  std::vector<std::string> columns = leading;
  auto add = [&columns](const std::string& c) {
    if (std::find(columns.begin(), columns.end(), c) == columns.end()) columns.push_back(c);
  };
  auto is_value = [](const json& v) { return v.is_number() || v.is_boolean() || v.is_null(); };
  for (const json& r : rows)
    for (const auto& [key, value] : r.items())
      if ((value.is_number() || value.is_boolean())) add(key);
  for (const json& r : rows)
    for (const auto& [key, value] : r.items()) {
      if (!value.is_object() || std::find(skip.begin(), skip.end(), key) != skip.end()) continue;
      for (const auto& [sub, v] : value.items())
        if (is_value(v)) add(key + "." + sub);
    }
  return columns;
}

json ColumnValue(const json& row, const std::string& column) {
  if (row.contains(column)) return row[column];
  const size_t dot = column.find('.');
  if (dot == std::string::npos) return nullptr;
  const std::string parent = column.substr(0, dot), key = column.substr(dot + 1);
  if (!row.contains(parent) || !row[parent].is_object() || !row[parent].contains(key))
    return nullptr;
  return row[parent][key];
}

StatusOr<json> BuildReportModel(const std::string& dir, const ReportOptions& options) {
  StatusOr<FolderKind> kind = DetectFolderKind(dir);
  if (!kind.ok()) return kind.status();
  StatusOr<Collected> c = Collect(dir, *kind, options);
  if (!c.ok()) return c.status();
  std::optional<Trajectory> truth;
  if (!c->gt.empty()) {
    StatusOr<Trajectory> gt = ReadTrajectory(c->gt);
    if (gt.ok() && !gt->empty())
      truth = std::move(*gt);
    else if (*kind == FolderKind::kRun)
      return Status::InvalidInput("--gt: " + (gt.ok() ? c->gt + ": empty" : gt.status().message()));
    else
      c->notes.push_back("ground truth " + c->gt + " not readable: drawn without it");
  }
  if (truth && *kind == FolderKind::kRun) AddRunEvalColumns(*truth, dir, &c->table);
  std::optional<PageFrame> frame;
  if (truth) frame = FrameOf(*truth);
  json runs = json::array();
  for (const RunEntry& r : c->runs) {
    if (!frame) {
      StatusOr<Trajectory> est = ReadTrajectory(r.dir + "/trajectory.tum");
      if (est.ok() && !est->empty()) frame = FrameOf(*est);
    }
    runs.push_back(RunJson(r, truth ? &*truth : nullptr, frame.value_or(PageFrame()), &c->notes));
  }
  const PageFrame shown = frame.value_or(PageFrame());
  if (!shown.origin.IsZero()) {
    char text[160];
    const Eigen::Vector3d& t = shown.origin.t_user_local;
    std::snprintf(text, sizeof(text), "positions are drawn relative to (%.3f, %.3f, %.3f) m",
                  t.x(), t.y(), t.z());
    c->notes.push_back(text);
  }
  json model = {{"title", c->title},
                {"kind", FolderKindName(*kind)},
                {"version", RVLIO_VERSION},
                {"runs", runs},
                {"table", c->table},
                {"gt", nullptr},
                {"cloud", nullptr}};
  if (truth) {
    model["gt"] = TrajectoryJson(*truth, shown);
    model["gt"]["file"] = c->gt;
  }
  for (const RunEntry& r : c->runs)
    if (r.name == c->map_run && IsFile(r.dir + "/map.pcd"))
      model["cloud"] = CloudJson(r.name, r.dir + "/map.pcd", shown.origin, options, &c->notes);
  for (const RunEntry& r : c->runs)
    if (r.name == c->map_run && IsFile(r.dir + "/control.csv"))
      model["control"] = ControlJson(r.dir + "/control.csv", shown.origin, &c->notes);
  model["notes"] = c->notes;
  return model;
}

StatusOr<ReportModel> BuildReport(const std::string& dir, const ReportOptions& options) {
  StatusOr<json> model = BuildReportModel(dir, options);
  if (!model.ok()) return model.status();
  ReportModel out;
  StatusOr<FolderKind> kind = DetectFolderKind(dir);
  if (kind.ok()) out.kind = *kind;
  out.title = model->value("title", "rvlio report");
  out.json = JsonText(*model, -1);
  return out;
}

}  // namespace rvlio::experiments::report

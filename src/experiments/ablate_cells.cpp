#include "rvlio/experiments/ablate_cells.h"

#include "ablate_records.h"

#include <cmath>
#include <filesystem>

#include "rvlio/api.h"
#include "rvlio/eval/evaluate.h"
#include "rvlio/eval/map_metrics.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/outputs/summary_json.h"

namespace rvlio::experiments::ablate {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// map_rms and map_completeness of run/map.pcd against the cell's reference
// cloud (as `rvlio eval --map`), the map moved by T_ref_est_poses (the run's
// poses aligned to the ground truth, as `compare` does); "" or why it failed.
std::string CollectMapMetrics(const Cell& cell, const Similarity3& T_ref_est, json* metrics) {
  if (cell.ref_map.empty()) return "";
  const PointCloudReadOptions xyz_only{false};
  StatusOr<PointCloudFile> map = ReadPointCloud(cell.RunDir() + "/map.pcd", xyz_only);
  if (!map.ok()) return "map eval: " + map.status().message();
  for (Eigen::Vector3d& p : map->points) p = T_ref_est * p;
  StatusOr<PointCloudFile> ref = ReadPointCloud(cell.ref_map, xyz_only);
  if (!ref.ok()) return "map eval: " + ref.status().message();
  StatusOr<MapEvalResult> r = EvaluateMap(map->points, ref->points, MapEvalOptions());
  if (!r.ok()) return "map eval: " + r.status().message();
  (*metrics)["map_rms"] = Number(r->accuracy.rmse);
  (*metrics)["map_completeness"] = Number(r->completeness);
  return "";
}

// A simulated cell: the run's degeneracy detection against the simulator's
// localizability.csv (as `rvlio eval --degeneracy`, its default truth
// threshold). A scoring error is a warning, not a failed cell (the
// trajectory metrics stand); the metrics stay null then.
void CollectDetectionMetrics(const Cell& cell, json* metrics, json* warnings) {
  if (cell.data_index < 0) return;
  (*metrics)["detect_precision"] = (*metrics)["detect_recall"] = nullptr;
  DegeneracyEvalArgs args;
  args.run_dir = cell.RunDir();
  args.truth_dir = fs::path(cell.gt).parent_path().string();
  args.gt_path = cell.gt;
  StatusOr<DegeneracyEvalResult> r = EvaluateDegeneracyFiles(args);
  if (!r.ok()) {
    warnings->push_back("detection: " + r.status().message());
    return;
  }
  (*metrics)["detect_precision"] = Number(r->scores.precision);
  (*metrics)["detect_recall"] = Number(r->scores.recall);
}

// The run's own figures from run/summary.json; false when it is unreadable.
bool CollectRunFigures(const Cell& cell, json* metrics) {
  const json summary = ReadJsonFile(cell.RunDir() + "/summary.json");
  if (!summary.is_object()) return false;
  const double scans = summary.value("scan_count", 0.0);
  (*metrics)["scans"] = scans;
  (*metrics)["ms_per_scan"] =
      summary.contains("per_scan_ms") ? summary["per_scan_ms"].value("median", 0.0) : 0.0;
  (*metrics)["rtf"] = summary.value("real_time_factor", 0.0);
  (*metrics)["rv_active_fraction"] =
      scans > 0 ? summary.value("rv_active_scans", 0.0) / scans : 0.0;
  (*metrics)["degenerate_fraction"] =
      scans > 0 ? summary.value("degenerate_scans", 0.0) / scans : 0.0;
  return true;
}

// Metrics from run/summary.json and the evaluation against ground truth
// (and the reference cloud). Returns "" or why the cell failed after a
// successful run.
std::string CollectMetrics(const Cell& cell, json* metrics, json* warnings) {
  if (!CollectRunFigures(cell, metrics))
    return "run finished but " + cell.RunDir() + "/summary.json is unreadable";
  for (const char* m : {"ate_rmse", "rpe_rmse", "axis_rmse", "axis_max", "end_point"})
    (*metrics)[m] = nullptr;
  if (!cell.ref_map.empty()) (*metrics)["map_rms"] = (*metrics)["map_completeness"] = nullptr;
  if (cell.gt.empty()) return CollectMapMetrics(cell, Similarity3(), metrics);
  StatusOr<Trajectory> gt = ReadTrajectory(cell.gt);
  if (!gt.ok()) return "eval: " + gt.status().message();
  StatusOr<Trajectory> est = ReadTrajectory(cell.RunDir() + "/trajectory.tum");
  if (!est.ok()) return "eval: " + est.status().message();
  StatusOr<EvalResult> r = Evaluate(*gt, *est, EvalOptions());
  if (!r.ok()) return "eval: " + r.status().message();
  (*metrics)["ate_rmse"] = Number(r->ape_m.rmse);
  (*metrics)["rpe_rmse"] = Number(r->rpe.trans_m.rmse);
  (*metrics)["axis_rmse"] = Number(r->along_axis.rmse_m);
  (*metrics)["axis_max"] = Number(r->along_axis.max_abs_m);
  (*metrics)["end_point"] = Number(r->end_point_error_m);
  *warnings = r->warnings;
  CollectDetectionMetrics(cell, metrics, warnings);
  return CollectMapMetrics(cell, r->T_ref_est_poses, metrics);
}

json CellHeader(const Cell& cell) {
  json params = json::object();
  for (const auto& [k, v] : cell.params) params[k] = v;
  return {{"format", 1},
          {"id", cell.id},
          {"hash", cell.hash},
          {"sequence", cell.sequence},
          {"seed", cell.has_seed ? json(cell.seed) : json(nullptr)},
          {"variant", cell.variant},
          {"params", params},
          {"label", cell.label},
          {"run_argv", cell.RunArgs()}};
}

Status WriteCellRecord(const Cell& cell, const json& record) {
  return WriteFileAtomically(cell.CellJson(), JsonText(record) + "\n");
}

}  // namespace

MetricSet MetricSetOf(const Plan& plan) { return {plan.HasRefMap(), plan.HasSimulated()}; }

const std::vector<MetricColumn>& MetricColumns(MetricSet set) {
  static const std::vector<MetricColumn> kAlways = {{"ate_rmse", "ATE [m]"},
                                                    {"rpe_rmse", "RPE [m]"},
                                                    {"axis_rmse", "axis RMSE [m]"},
                                                    {"axis_max", "axis max [m]"},
                                                    {"end_point", "end [m]"},
                                                    {"ms_per_scan", "ms/scan"},
                                                    {"rtf", "RTF"},
                                                    {"rv_active_fraction", "RV active"},
                                                    {"degenerate_fraction", "degenerate"}};
  static const std::vector<std::vector<MetricColumn>> kSets = [] {
    std::vector<std::vector<MetricColumn>> sets(4, kAlways);
    for (int i = 0; i < 4; ++i) {
      if (i & 1)
        sets[i].insert(sets[i].end(),
                       {{"map_rms", "map RMS [m]"}, {"map_completeness", "completeness"}});
      if (i & 2)
        sets[i].insert(sets[i].end(),
                       {{"detect_precision", "precision"}, {"detect_recall", "recall"}});
    }
    return sets;
  }();
  return kSets[(set.map ? 1 : 0) + (set.detection ? 2 : 0)];
}

const char* CellStatusName(CellStatus status) {
  switch (status) {
    case CellStatus::kMissing:
      return "missing";
    case CellStatus::kDone:
      return "done";
    case CellStatus::kDiverged:
      return "diverged";
    case CellStatus::kFailed:
      return "failed";
  }
  return "missing";  // not reached: every status is listed above
}

StatusOr<CellStatus> RecordCell(const Cell& cell, const CellRunEnd& end) {
  json r = CellHeader(cell);
  r["exit_code"] = end.exit_code ? json(*end.exit_code) : json(nullptr);
  r["wall_s"] = end.wall_s;
  r["stderr_tail"] = end.log_tail;
  json metrics = json::object(), warnings = json::array();
  // A diverged run went to the end: the cell is finished, its metrics are
  // kept, and its status says so.
  const bool ran = end.exit_code == 0 || end.diverged;
  const std::string error =
      ran ? CollectMetrics(cell, &metrics, &warnings) : "rvlio run " + end.how;
  const CellStatus status = !error.empty() ? CellStatus::kFailed
                            : end.diverged ? CellStatus::kDiverged
                                           : CellStatus::kDone;
  r["status"] = CellStatusName(status);
  r["error"] = error.empty() ? json(nullptr) : json(error);
  r["metrics"] = metrics;
  r["eval_warnings"] = warnings;
  if (Status s = WriteCellRecord(cell, r); !s.ok()) return s;
  return status;
}

StatusOr<CellStatus> RecordDataFailure(const Cell& cell, const DataItem& d,
                                       const std::string& log_tail) {
  json r = CellHeader(cell);
  r["status"] = CellStatusName(CellStatus::kFailed);
  r["exit_code"] = nullptr;
  r["error"] = "data " + d.id + " could not be simulated (see " + d.dir + "/simulate.log)";
  r["stderr_tail"] = log_tail;
  r["metrics"] = json::object();
  r["wall_s"] = 0.0;
  if (Status s = WriteCellRecord(cell, r); !s.ok()) return s;
  return CellStatus::kFailed;
}

json ReadCellRecord(const Cell& cell) {
  json r = ReadJsonFile(cell.CellJson());
  if (!r.is_object() || r.value("hash", "") != cell.hash) return nullptr;
  return r;
}

CellStatus RecordStatus(const json& record) {
  if (!record.is_object()) return CellStatus::kMissing;
  const std::string status = record.value("status", "");
  for (CellStatus s : {CellStatus::kDone, CellStatus::kDiverged})
    if (status == CellStatusName(s)) return s;
  return CellStatus::kFailed;
}

CellStatus ReadCellStatus(const Cell& cell) { return RecordStatus(ReadCellRecord(cell)); }

}  // namespace rvlio::experiments::ablate

// EvaluateFiles and EvalJson (rvlio/api.h): `rvlio eval` without its
// argument parsing and table; EvaluateDegeneracyFiles and DegeneracyEvalJson:
// the files of `rvlio eval --degeneracy RUN_DIR --truth SIM_DIR` read into
// labels for ScoreDegeneracy (eval/degeneracy.h).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <utility>

#include "rvlio/api.h"
#include "rvlio/api/result_json.h"
#include "rvlio/api/refine_checkpoint.h"
#include "rvlio/eval/time_matching.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/outputs/run_outputs.h"
#include "rvlio/formats/trajectory_io.h"

namespace rvlio {
namespace {

// 10 significant digits; null for a non-finite value.
nlohmann::json Num(double v) {
  if (!std::isfinite(v)) return nullptr;
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.10g", v);
  return std::strtod(buf, nullptr);
}

nlohmann::json StatsJson(const ErrorStats& s) {
  return {{"rmse", Num(s.rmse)}, {"mean", Num(s.mean)}, {"median", Num(s.median)},
          {"std", Num(s.std)},   {"min", Num(s.min)},   {"max", Num(s.max)}};
}

nlohmann::json DistanceJson(const ErrorStats& s) {
  return {{"count", s.count},        {"mean", Num(s.mean)}, {"rms", Num(s.rmse)},
          {"median", Num(s.median)}, {"p95", Num(s.p95)},   {"max", Num(s.max)}};
}

nlohmann::json VectorJson(const Eigen::Vector3d& v) { return {Num(v.x()), Num(v.y()), Num(v.z())}; }

namespace fs = std::filesystem;

// The columns that make a label, by header name.
struct LabelColumns {
  const char* degenerate;
  const char* weak_dir[3];
};
constexpr LabelColumns kDegeneracyColumns{"degenerate", {"weak_dir_x", "weak_dir_y", "weak_dir_z"}};
constexpr LabelColumns kRvColumns{"rv_active", {"n_alpha_x", "n_alpha_y", "n_alpha_z"}};

StatusOr<const std::vector<double>*> Column(const ScanTable& table, const std::string& path,
                                            const std::string& name) {
  const std::vector<double>* c = table.Find(name);
  if (!c) return Status::InvalidInput(path + ": no column '" + name + "'");
  return c;
}

// The labels of a table; `direction_required`: every row needs a finite
// direction (truth), else only a flagged row may have one (empty: none).
StatusOr<std::vector<DegeneracyLabel>> ReadLabels(const std::string& path,
                                                  const LabelColumns& names,
                                                  bool direction_required) {
  StatusOr<ScanTable> table = ReadScanTable(path);
  if (!table.ok()) return table.status();
  const std::vector<double>* cols[5];
  const char* wanted[5] = {"t", names.degenerate, names.weak_dir[0], names.weak_dir[1],
                           names.weak_dir[2]};
  for (int k = 0; k < 5; ++k) {
    StatusOr<const std::vector<double>*> c = Column(*table, path, wanted[k]);
    if (!c.ok()) return c.status();
    cols[k] = *c;
  }
  std::vector<DegeneracyLabel> labels(cols[0]->size());
  for (size_t i = 0; i < labels.size(); ++i) {
    const double t = (*cols[0])[i], flag = (*cols[1])[i];
    const Eigen::Vector3d dir((*cols[2])[i], (*cols[3])[i], (*cols[4])[i]);
    const std::string row = path + ": data row " + std::to_string(i + 1) + ": ";
    if (!std::isfinite(t)) return Status::InvalidInput(row + "t is not a finite number");
    if (flag != 0.0 && flag != 1.0)
      return Status::InvalidInput(row + names.degenerate + " is not 0 or 1");
    if (direction_required && !dir.allFinite())
      return Status::InvalidInput(row + "the weak direction is not finite");
    labels[i].t_ns = SecondsToNs(t);
    labels[i].degenerate = flag == 1.0;
    labels[i].weak_dir_world = dir.allFinite() ? dir : Eigen::Vector3d::Zero();
  }
  if (labels.empty()) return Status::InvalidInput(path + ": no rows");
  return labels;
}

// The truth's flags from its ratio column: degenerate when below `ratio`.
Status Rethreshold(const std::string& path, double ratio, std::vector<DegeneracyLabel>* truth) {
  StatusOr<ScanTable> table = ReadScanTable(path);
  if (!table.ok()) return table.status();
  StatusOr<const std::vector<double>*> column = Column(*table, path, "ratio");
  if (!column.ok()) return column.status();
  for (size_t i = 0; i < truth->size(); ++i) {
    const double v = (**column)[i];
    if (!std::isfinite(v))
      return Status::InvalidInput(path + ": data row " + std::to_string(i + 1) +
                                  ": ratio is not a finite number");
    (*truth)[i].degenerate = v < ratio;
  }
  return Status::Ok();
}

// The one NAME_gt.tum of a simulation folder.
StatusOr<std::string> FindGroundTruth(const std::string& truth_dir) {
  std::vector<std::string> found;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(truth_dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() > 7 && name.compare(name.size() - 7, 7, "_gt.tum") == 0)
      found.push_back(e.path().string());
  }
  if (ec) return Status::InvalidInput(truth_dir + ": cannot list (" + ec.message() + ")");
  if (found.size() != 1)
    return Status::InvalidInput(truth_dir + ": " + std::to_string(found.size()) +
                                " ground truths (*_gt.tum); name one with --gt FILE");
  return found.front();
}

}  // namespace

StatusOr<EvalResult> EvaluateFiles(const std::string& gt_path, const std::string& est_path,
                                   const EvalOptions& options) {
  StatusOr<Trajectory> gt = ReadTrajectory(gt_path);
  if (!gt.ok()) return gt.status();
  StatusOr<Trajectory> est = ReadTrajectory(est_path);
  if (!est.ok()) return est.status();
  return Evaluate(*gt, *est, options);
}

nlohmann::json EvalJson(const EvalResult& r) {
  nlohmann::json rpe = StatsJson(r.rpe.trans_m);
  rpe["pairs"] = r.rpe.pairs;
  return {{"matched", r.matched},
          {"align", AlignModeName(r.align)},
          {"scale", Num(r.T_ref_est.scale)},
          {"ape", StatsJson(r.ape_m)},
          {"ape_rot_deg", StatsJson(r.ape_rot_deg)},
          {"rpe", rpe},
          {"rpe_rot_deg", StatsJson(r.rpe.rot_deg)},
          {"end_point_error", Num(r.end_point_error_m)},
          {"along_axis", {{"rmse", Num(r.along_axis.rmse_m)}, {"max", Num(r.along_axis.max_abs_m)}}},
          {"warnings", r.warnings}};
}

StatusOr<MapEvalResult> EvaluateMapFiles(const std::string& map_path, const std::string& ref_path,
                                         const MapEvalOptions& options,
                                         const MapEvalProgress& progress) {
  const PointCloudReadOptions xyz_only{false};
  StatusOr<PointCloudFile> map = ReadPointCloud(map_path, xyz_only);
  if (!map.ok()) return map.status();
  StatusOr<PointCloudFile> ref = ReadPointCloud(ref_path, xyz_only);
  if (!ref.ok()) return ref.status();
  StatusOr<MapEvalResult> r =
      EvaluateMap(std::move(map->points), std::move(ref->points), options, progress);
  if (!r.ok()) return Status::InvalidInput(map_path + " vs " + ref_path + ": " + r.status().message());
  return r;
}

nlohmann::json MapEvalJson(const MapEvalResult& r) {
  nlohmann::json profile = nlohmann::json::array();
  for (const MapProfileBin& b : r.profile)
    profile.push_back({{"chainage", Num(b.chainage_m)},
                       {"map_points", b.map_points},
                       {"map_with_plane", b.map_with_plane},
                       {"rms", Num(b.rms_m)},
                       {"median", Num(b.median_m)},
                       {"p95", Num(b.p95_m)},
                       {"ref_points", b.ref_points},
                       {"completeness", Num(b.completeness)}});
  return {{"map_points", r.map_points},
          {"ref_points", r.ref_points},
          {"max_distance", Num(r.max_distance_m)},
          {"inliers", r.inliers},
          {"no_plane", r.no_plane},
          {"outlier_fraction", Num(r.outlier_fraction)},
          {"accuracy", DistanceJson(r.accuracy)},
          {"nearest", DistanceJson(r.nearest)},
          {"completeness", Num(r.completeness)},
          {"chamfer", Num(r.chamfer_m)},
          {"chamfer_definition",
           "0.5 * (mean over map points of min(d(map, ref), D) + mean over reference points of "
           "min(d(ref, map), D)), nearest-point distances"},
          {"axis", {{"origin", VectorJson(r.axis_origin)}, {"direction", VectorJson(r.axis_direction)}}},
          {"profile", profile}};
}

namespace {

nlohmann::json ReadJsonOrNull(const std::string& path) {
  std::ifstream in(path);
  if (!in) return nullptr;
  nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  return j.is_discarded() ? nlohmann::json() : j;
}

// The recording RUN_DIR/summary.json says the run read, when that file is
// still there (a relative path is taken from the current folder).
std::string RunRecording(const std::string& run_dir) {
  const nlohmann::json summary = ReadJsonOrNull((fs::path(run_dir) / "summary.json").string());
  if (!summary.is_object() || !summary.contains("bag") || !summary["bag"].is_string()) return "";
  std::error_code ec;
  const std::string bag = summary["bag"].get<std::string>();
  return fs::exists(bag, ec) ? bag : "";
}

// SIM_DIR/simulation.json (written by `rvlio simulate`, api.h
// kSimulationFile) against the truth read and the run's recording: the
// truth's scan count must be the one simulated, and the recording the run
// read (summary.json's bag, when it still exists) must be the simulated one:
// the same file, or one of the same content (recording_hash). A folder
// without simulation.json (older simulations) passes to the stamp check.
Status CheckSimulationRecord(const std::string& run_dir, const std::string& truth_dir,
                             const std::string& truth_path, size_t truth_scans) {
  const std::string record_path = (fs::path(truth_dir) / kSimulationFile).string();
  const nlohmann::json record = ReadJsonOrNull(record_path);
  if (record.is_null()) return Status::Ok();
  const size_t simulated = record.value("localizability_scans", size_t{0});
  if (simulated != truth_scans)
    return Status::InvalidInput(truth_path + " has " + std::to_string(truth_scans) + " scans, " +
                                record_path + " records " + std::to_string(simulated) +
                                ": the folder mixes files of two simulations");
  const std::string read = RunRecording(run_dir);
  if (read.empty()) return Status::Ok();
  const std::string simulated_file = (fs::path(truth_dir) / record.value("recording", "")).string();
  std::error_code ec;
  if (fs::equivalent(read, simulated_file, ec)) return Status::Ok();
  StatusOr<uint64_t> hash = FileContentHash(read);
  if (hash.ok() && HashText(*hash) == record.value("recording_hash", "")) return Status::Ok();
  return Status::InvalidInput(
      run_dir + " is a run of " + read + ", not of the recording " + simulated_file +
      " that " + truth_dir + " simulated (preset " + record.value("preset", "?") + ", seed " +
      record.value("seed", nlohmann::json()).dump() + "): the truth is of another simulation");
}

// Every scan of the run must have a truth scan at its stamp (the run's scans
// are the simulation's, less those it dropped): a run scan without one means
// a truth of another recording (another duration, start or rate).
Status CheckStampsAgree(const std::vector<DegeneracyLabel>& run,
                        const std::vector<DegeneracyLabel>& truth, double max_dt_s,
                        const std::string& scans_path, const std::string& truth_path) {
  Trajectory run_stamps(run.size()), truth_stamps(truth.size());
  for (size_t i = 0; i < run.size(); ++i) run_stamps[i].t_ns = run[i].t_ns;
  for (size_t i = 0; i < truth.size(); ++i) truth_stamps[i].t_ns = truth[i].t_ns;
  StatusOr<Association> a = Associate(run_stamps, truth_stamps, max_dt_s);
  const size_t matched = a.ok() ? a->size() : 0;
  if (matched == run.size()) return Status::Ok();
  char dt[32];
  std::snprintf(dt, sizeof(dt), "%g", max_dt_s);
  return Status::InvalidInput(
      std::to_string(run.size() - matched) + " of the " + std::to_string(run.size()) +
      " scans of " + scans_path + " have no scan of " + truth_path + " within " + dt +
      " s (" + std::to_string(truth.size()) + " there): the truth is of another recording");
}

}  // namespace

StatusOr<DegeneracyEvalResult> EvaluateDegeneracyFiles(const DegeneracyEvalArgs& args) {
  const std::string &run_dir = args.run_dir, &truth_dir = args.truth_dir;
  if (!(args.degenerate_ratio >= 0.0))
    return Status::InvalidInput("degenerate ratio " + std::to_string(args.degenerate_ratio) +
                                " is not a number >= 0");
  DegeneracyEvalResult r;
  r.scans_path = (fs::path(run_dir) / "scans.csv").string();
  r.est_path = (fs::path(run_dir) / "trajectory.tum").string();
  r.truth_path = (fs::path(truth_dir) / "localizability.csv").string();
  StatusOr<ScanTable> header = ReadScanTable(r.scans_path);
  if (!header.ok()) return header.status();
  const bool own = header->Find(kDegeneracyColumns.degenerate) != nullptr;
  r.detection_columns = own ? "degenerate,weak_dir" : "rv_active,n_alpha";
  StatusOr<std::vector<DegeneracyLabel>> detected =
      ReadLabels(r.scans_path, own ? kDegeneracyColumns : kRvColumns, false);
  if (!detected.ok()) return detected.status();
  StatusOr<std::vector<DegeneracyLabel>> truth = ReadLabels(r.truth_path, kDegeneracyColumns, true);
  if (!truth.ok()) return truth.status();
  if (args.degenerate_ratio > 0.0) {
    if (Status s = Rethreshold(r.truth_path, args.degenerate_ratio, &*truth); !s.ok()) return s;
  }
  if (Status s = CheckSimulationRecord(run_dir, truth_dir, r.truth_path, truth->size()); !s.ok())
    return s;
  if (Status s = CheckStampsAgree(*detected, *truth, args.eval.max_dt, r.scans_path, r.truth_path);
      !s.ok())
    return s;
  r.gt_path = args.gt_path;
  if (r.gt_path.empty()) {
    StatusOr<std::string> found = FindGroundTruth(truth_dir);
    if (!found.ok()) return found.status();
    r.gt_path = *found;
  }
  StatusOr<Trajectory> gt = ReadTrajectory(r.gt_path);
  if (!gt.ok()) return gt.status();
  StatusOr<Trajectory> est = ReadTrajectory(r.est_path);
  if (!est.ok()) return est.status();
  StatusOr<DegeneracyScores> scores = ScoreDegeneracy(*truth, *detected, *gt, *est, args.eval);
  if (!scores.ok())
    return Status::InvalidInput(r.scans_path + " vs " + r.truth_path + ": " +
                                scores.status().message());
  r.truth_scans = truth->size();
  r.run_scans = detected->size();
  r.scores = *scores;
  return r;
}

nlohmann::json DegeneracyEvalJson(const DegeneracyEvalResult& r) {
  const DegeneracyScores& s = r.scores;
  return {{"detection_columns", r.detection_columns},
          {"truth_scans", r.truth_scans},
          {"run_scans", r.run_scans},
          {"matched", s.matched},
          {"true_positive", s.true_positive},
          {"false_positive", s.false_positive},
          {"false_negative", s.false_negative},
          {"true_negative", s.true_negative},
          {"precision", Num(s.precision)},
          {"recall", Num(s.recall)},
          {"angle_deg",
           {{"count", s.angle_deg.count},
            {"mean", Num(s.angle_deg.mean)},
            {"median", Num(s.angle_deg.median)},
            {"max", s.angle_deg.count ? Num(s.angle_deg.max) : nullptr}}},
          {"along_weak",
           {{"scans", s.error_scans},
            {"rms", Num(s.along_weak_rms_m)},
            {"rms_degenerate", Num(s.along_weak_rms_degenerate_m)},
            {"final", Num(s.along_weak_final_m)},
            {"growth_per_100m", Num(s.along_weak_growth_per_100m)},
            {"path_length", Num(s.path_length_m)}}},
          {"warnings", s.warnings}};
}

}  // namespace rvlio

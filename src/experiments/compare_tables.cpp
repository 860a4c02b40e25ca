// compare.csv, compare.md and compare.json from a CompareResult.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include <nlohmann/json.hpp>

#include "csv_text.h"
#include "rvlio/api/result_json.h"
#include "rvlio/common/text.h"
#include "rvlio/experiments/compare.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/outputs/summary_json.h"
#include "rvlio/version.h"

namespace rvlio::experiments {
namespace {

std::string FixedOrDash(double v, int decimals) {
  return std::isfinite(v) ? FormatFixed(v, decimals) : std::string("-");
}

nlohmann::json Num(double v) {
  if (!std::isfinite(v)) return nullptr;
  return std::strtod(FormatFinite(v, 10).c_str(), nullptr);
}

const char* kCsvHeader =
    "variant,label,status,exit_code,init,scans,ate_rmse_m,rpe_rmse_m,axis_max_m,end_point_m,"
    "ms_per_scan,real_time_factor\n";

// The map columns (with a reference cloud): accuracy RMS and completeness, or empty.
std::string MapCsvFields(const CompareRow& r) {
  if (!r.map_eval) return ",,";
  return "," + FormatFinite(r.map_eval->accuracy.rmse, 10) + "," +
         FormatFinite(r.map_eval->completeness, 10);
}

std::string MeasuredCsvFields(const CompareRow& r) {
  const EvalResult& e = *r.eval;
  std::string fields;
  for (double v : {e.ape_m.rmse, e.rpe.trans_m.rmse, e.along_axis.max_abs_m, e.end_point_error_m,
                   r.ms_per_scan, r.real_time_factor})
    fields += "," + FormatFinite(v, 10);
  return fields;
}

std::string MarkdownRow(const CompareRow& r, bool with_map) {
  std::ostringstream os;
  os << "| " << r.label << (r.diverged ? " (**diverged**)" : "") << " | ";
  if (r.interrupted) return os.str() + "interrupted | | | | | |\n";
  if (!r.measured())
    return os.str() + "failed (exit " + std::to_string(r.exit_code) + ") | | | | | |\n";
  const EvalResult& e = *r.eval;
  os << FixedOrDash(e.ape_m.rmse, 4) << " | " << FixedOrDash(e.rpe.trans_m.rmse, 4) << " | "
     << FixedOrDash(e.along_axis.max_abs_m, 4) << " | " << FixedOrDash(e.end_point_error_m, 4)
     << " | " << FixedOrDash(r.ms_per_scan, 2) << (r.name == kRefineStep ? " (wall)" : "") << " | "
     << FixedOrDash(r.real_time_factor, 1) << "x |";
  if (with_map)
    os << " " << (r.map_eval ? FixedOrDash(r.map_eval->accuracy.rmse, 4) : "-") << " | "
       << (r.map_eval ? FixedOrDash(r.map_eval->completeness, 3) : "-") << " |";
  os << "\n";
  return os.str();
}

// A row's evaluation: `rvlio eval --json`'s object (EvalJson) without the
// scale and the RPE's pair count, which compare.json has never carried.
nlohmann::json CompareEvalJson(const EvalResult& e) {
  nlohmann::json j = EvalJson(e);
  j.erase("scale");
  j["rpe"].erase("pairs");
  return j;
}

nlohmann::json RowJson(const CompareRequest& req, const CompareRow& r) {
  nlohmann::json j = {{"variant", r.name},        {"label", r.label},
                      {"status", r.StatusName()}, {"diverged", r.diverged},
                      {"exit_code", r.exit_code}, {"dir", req.out_dir + "/" + r.name},
                      {"overrides", r.overrides}, {"wall_s", Num(r.wall_s)}};
  if (!r.init.empty()) j["init"] = r.init;
  if (!r.eval_error.empty()) j["error"] = r.eval_error;
  if (!r.measured()) return j;
  const EvalResult& e = *r.eval;
  j["scans"] = r.scans;
  j["ate_rmse_m"] = Num(e.ape_m.rmse);
  j["rpe_rmse_m"] = Num(e.rpe.trans_m.rmse);
  j["axis_max_m"] = Num(e.along_axis.max_abs_m);
  j["end_point_m"] = Num(e.end_point_error_m);
  j["ms_per_scan"] = Num(r.ms_per_scan);
  j["ms_per_scan_kind"] = r.name == kRefineStep ? "wall, batch solve / scans" : "CPU, median";
  j["real_time_factor"] = Num(r.real_time_factor);
  if (r.map_eval) {
    j["map_rms_m"] = Num(r.map_eval->accuracy.rmse);
    j["map_completeness"] = Num(r.map_eval->completeness);
    j["map_eval"] = MapEvalJson(*r.map_eval);
  }
  j["eval"] = CompareEvalJson(e);
  return j;
}

}  // namespace

std::string CompareAlignName(const CompareResult& result) {
  for (const CompareRow& r : result.rows)
    if (r.measured()) return AlignModeName(r.eval->align);
  return "se3";
}

std::string CompareCsv(const CompareRequest& req, const CompareResult& result) {
  const bool with_map = !req.ref_map.empty();
  std::string text = kCsvHeader;
  if (with_map) text.insert(text.size() - 1, ",map_rms_m,map_completeness");
  for (const CompareRow& r : result.rows) {
    text += r.name + "," + CsvField(r.label) + "," + r.StatusName() + "," +
            std::to_string(r.exit_code) + "," + r.init + "," + std::to_string(r.scans);
    text += r.measured() ? MeasuredCsvFields(r) : ",,,,,,";
    if (with_map) text += r.measured() ? MapCsvFields(r) : ",,";
    text += "\n";
  }
  return text;
}

std::string CompareMarkdown(const CompareRequest& req, const CompareResult& result) {
  std::ostringstream os;
  const bool with_map = !req.ref_map.empty();
  os << "| variant | ATE [m] | RPE [m] | along-axis max [m] | end-point [m] | ms/scan | "
        "real-time factor |"
     << (with_map ? " map RMS [m] | completeness |" : "") << "\n|---|---|---|---|---|---|---|"
     << (with_map ? "---|---|" : "") << "\n";
  for (const CompareRow& r : result.rows) os << MarkdownRow(r, with_map);
  os << "\nBag `" << req.bag << "`, ground truth `" << req.gt << "`. ATE: translation RMSE after "
     << CompareAlignName(result)
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

std::string CompareJsonText(const CompareRequest& req, const CompareResult& result,
                            const ComparePlots& plots) {
  nlohmann::json j;
  j["version"] = RVLIO_VERSION;
  j["command"] = "compare";
  j["bag"] = req.bag;
  j["gt"] = req.gt;
  if (!req.ref_map.empty()) j["ref_map"] = req.ref_map;
  j["config"] = req.config_files;
  j["set"] = req.overrides;
  j["align"] = CompareAlignName(result);
  j["variants"] = nlohmann::json::array();
  for (const CompareRow& r : result.rows) j["variants"].push_back(RowJson(req, r));
  j["plots"] = {{"status", plots.status}, {"message", plots.message}, {"files", plots.files}};
  return JsonText(j) + "\n";
}

Status WriteCompareTables(const CompareRequest& req, const CompareResult& result) {
  if (Status s = WriteFileAtomically(req.out_dir + "/compare.csv", CompareCsv(req, result));
      !s.ok())
    return s;
  return WriteFileAtomically(req.out_dir + "/compare.md", CompareMarkdown(req, result));
}

Status WriteCompareJson(const CompareRequest& req, const CompareResult& result,
                        const ComparePlots& plots) {
  return WriteFileAtomically(req.out_dir + "/compare.json", CompareJsonText(req, result, plots));
}

}  // namespace rvlio::experiments

// rvlio eval: ATE/RPE of an estimated trajectory against ground truth with the
// definitions of evo (docs/design.md "Evaluation"), or with --map a map against
// a reference cloud (docs/map_eval.md). Argument parsing and output only;
// EvaluateFiles / EvaluateMapFiles (rvlio/api.h) and EvalJson / MapEvalJson (rvlio/api/result_json.h)
// do the work.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "cli.h"
#include "commands.h"
#include "rvlio/common/number_text.h"
#include "rvlio/outputs/summary_json.h"
#include "common_options.h"
#include "rvlio/api.h"
#include "rvlio/api/result_json.h"

namespace rvlio::cli {
namespace {

constexpr const char* kEval = "eval";

CommandSpec EvalSpec() {
  return {
      kEval,
      "ATE/RPE of an estimated trajectory against ground truth, with the definitions of the evo\n"
      "tool. Trajectories are TUM (t x y z qx qy qz qw) or KITTI (3x4 rows, assumed 10 Hz)\n"
      "files, detected by their column count.\n"
      "With --map and --ref-map instead: the map's accuracy against a reference cloud (PCD or\n"
      "PLY, same frame): point-to-plane and nearest-point distances, completeness, Chamfer\n"
      "distance, outliers and a profile along the reference's principal axis\n"
      "(docs/map_eval.md).\n"
      "With --degeneracy RUN_DIR --truth SIM_DIR instead: the run's per-scan degeneracy\n"
      "detection (scans.csv) against the simulator's true localizability\n"
      "(SIM_DIR/localizability.csv): precision, recall, weak-direction angle and the error\n"
      "along the true weak direction (docs/degeneracy_truth.md). Exit status 2 on bad input.",
      {{"gt", "FILE", "reference trajectory (trajectory mode)", false, false},
       {"est", "FILE", "estimated trajectory (trajectory mode)", false, false},
       {"map", "FILE", "map to judge, PCD or PLY (map mode)", false, false},
       {"ref-map", "FILE", "reference cloud, PCD or PLY (map mode)", false, false},
       {"max-distance", "M", "map mode: inlier / completeness threshold D (default 0.1)", false,
        false},
       {"profile-step", "M", "map mode: chainage bin of the profile (default 1)", false, false},
       {"degeneracy", "RUN_DIR", "a run folder (scans.csv, trajectory.tum) to score (degeneracy mode)",
        false, false},
       {"truth", "SIM_DIR", "degeneracy mode: an `rvlio simulate` folder (localizability.csv, "
        "*_gt.tum; --gt FILE names the ground truth)", false, false},
       {"truth-ratio", "R", "degeneracy mode: a true scan is degenerate when lambda_min / "
        "lambda_max < R (default: the simulation's flags, localizability.degenerate_ratio)",
        false, false},
       {"align", "MODE", "se3 | sim3 | origin | none (default se3)", false, false},
       {"rpe-delta", "N", "RPE step (default 1)", false, false},
       {"rpe-unit", "UNIT", "frames | meters (default frames)", false, false},
       {"max-dt", "S", "association tolerance in seconds (default 0.01)", false, false},
       {"json", "", "print one JSON object instead of the table", false, false}}};
}

// Fills `options` from the arguments; returns an error message or "".
std::string ReadOptions(const Args& args, EvalOptions* options) {
  options->align = args.Get("align", options->align);
  options->rpe_unit = args.Get("rpe-unit", options->rpe_unit);
  for (auto [flag, field] : {std::pair<const char*, double*>{"rpe-delta", &options->rpe_delta},
                             std::pair<const char*, double*>{"max-dt", &options->max_dt}}) {
    if (args.Has(flag) && !ParseNumber(args.Get(flag), field))
      return std::string("--") + flag + " '" + args.Get(flag) + "' is not a number";
  }
  if (options->align != "se3" && options->align != "sim3" && options->align != "origin" &&
      options->align != "none")
    return "--align '" + options->align + "' is not one of se3|sim3|origin|none";
  if (options->rpe_unit != "frames" && options->rpe_unit != "meters")
    return "--rpe-unit '" + options->rpe_unit + "' is not one of frames|meters";
  return "";
}

void PrintJson(const EvalResult& r) { std::cout << JsonText(EvalJson(r), -1) << "\n"; }

void PrintRow(const char* label, const ErrorStats& s, const std::string& note = "") {
  std::printf("%-14s %12.6f %12.6f %12.6f %12.6f %12.6f %12.6f%s\n", label, s.rmse, s.mean,
              s.median, s.std, s.min, s.max, note.c_str());
}

void PrintTable(const EvalResult& r, const EvalOptions& options) {
  std::printf("matched poses  %zu   align %s   scale %.10g\n\n", r.matched, AlignModeName(r.align),
              r.T_ref_est.scale);
  std::printf("%-14s %12s %12s %12s %12s %12s %12s\n", "metric", "rmse", "mean", "median", "std",
              "min", "max");
  PrintRow("APE [m]", r.ape_m);
  PrintRow("APE [deg]", r.ape_rot_deg);
  char note[96];
  std::snprintf(note, sizeof(note), "   (%zu pairs, delta %g %s)", r.rpe.pairs, options.rpe_delta,
                options.rpe_unit.c_str());
  PrintRow("RPE [m]", r.rpe.trans_m, note);
  PrintRow("RPE [deg]", r.rpe.rot_deg);
  std::printf("\nend-point error [m]   %.6f\n", r.end_point_error_m);
  std::printf("along-axis [m]        rmse %.6f   max %.6f\n", r.along_axis.rmse_m,
              r.along_axis.max_abs_m);
}

std::string ReadMapOptions(const Args& args, MapEvalOptions* options) {
  for (auto [flag, field] :
       {std::pair<const char*, double*>{"max-distance", &options->max_distance},
        std::pair<const char*, double*>{"profile-step", &options->profile_step}}) {
    if (!args.Has(flag)) continue;
    if (!ParseNumber(args.Get(flag), field) || *field <= 0.0)
      return std::string("--") + flag + " '" + args.Get(flag) + "' is not a positive number";
  }
  return "";
}

void PrintMapRow(const char* label, const ErrorStats& s) {
  std::printf("%-16s %10.6f %10.6f %10.6f %10.6f %10.6f %10zu\n", label, s.mean, s.rmse, s.median,
              s.p95, s.max, s.count);
}

// The summary, then the (at most) five profile bins of largest RMS.
void PrintMapTable(const MapEvalResult& r, const std::string& map_path,
                   const std::string& ref_path) {
  std::printf("map %s (%zu points) vs reference %s (%zu points), D = %g m\n\n", map_path.c_str(),
              r.map_points, ref_path.c_str(), r.ref_points, r.max_distance_m);
  std::printf("%-16s %10s %10s %10s %10s %10s %10s\n", "distance [m]", "mean", "rms", "median",
              "p95", "max", "points");
  PrintMapRow("point-to-plane", r.accuracy);
  PrintMapRow("nearest point", r.nearest);
  std::printf("\ncompleteness      %.4f   (reference points with a map point within D)\n",
              r.completeness);
  std::printf("chamfer [m]       %.6f (mean of both directions, distances capped at D)\n",
              r.chamfer_m);
  std::printf("outliers          %.4f   (map points with no reference point within D)\n",
              r.outlier_fraction);
  std::printf("no plane          %zu      (inliers at reference edges or corners)\n", r.no_plane);
  std::vector<const MapProfileBin*> worst;
  for (const MapProfileBin& b : r.profile)
    if (b.map_with_plane > 0) worst.push_back(&b);
  std::sort(worst.begin(), worst.end(),
            [](const MapProfileBin* a, const MapProfileBin* b) { return a->rms_m > b->rms_m; });
  if (worst.size() > 5) worst.resize(5);
  std::printf("\nprofile: %zu bins along the reference's principal axis (all in --json); largest "
              "rms:\n",
              r.profile.size());
  std::printf("%12s %10s %10s %10s %12s\n", "chainage [m]", "rms [m]", "p95 [m]", "points",
              "completeness");
  for (const MapProfileBin* b : worst)
    std::printf("%12.1f %10.6f %10.6f %10zu %12.4f\n", b->chainage_m, b->rms_m, b->p95_m,
                b->map_with_plane, b->completeness);
}

void PrintDegeneracyTable(const DegeneracyEvalResult& r) {
  const DegeneracyScores& s = r.scores;
  std::printf("detection %s of %s vs truth %s\n", r.detection_columns.c_str(),
              r.scans_path.c_str(), r.truth_path.c_str());
  std::printf("matched scans  %zu of %zu (run) / %zu (truth)\n\n", s.matched, r.run_scans,
              r.truth_scans);
  std::printf("degenerate     true %zu   flagged %zu   both %zu\n",
              s.true_positive + s.false_negative, s.true_positive + s.false_positive,
              s.true_positive);
  std::printf("precision      %.4f\nrecall         %.4f\n", s.precision, s.recall);
  std::printf("weak-direction angle [deg]  mean %.3f   median %.3f   (%zu scans flagged by both)\n",
              s.angle_deg.mean, s.angle_deg.median, s.angle_deg.count);
  std::printf("error along the true weak direction [m]  rms %.4f   rms (degenerate) %.4f   "
              "final %.4f\n",
              s.along_weak_rms_m, s.along_weak_rms_degenerate_m, s.along_weak_final_m);
  std::printf("growth [m per 100 m]  %.4f   (path %.1f m)\n", s.along_weak_growth_per_100m,
              s.path_length_m);
}

int EvalDegeneracy(const Args& args) {
  if (args.Has("map") || args.Has("ref-map") || args.Has("est"))
    return Fail(kEval, "--degeneracy (degeneracy mode) cannot be combined with --map/--ref-map/--est");
  if (!args.Has("truth")) return Fail(kEval, "--degeneracy RUN_DIR needs --truth SIM_DIR");
  DegeneracyEvalArgs d;
  if (std::string error = ReadOptions(args, &d.eval); !error.empty()) return Fail(kEval, error);
  d.run_dir = args.Get("degeneracy");
  d.truth_dir = args.Get("truth");
  d.gt_path = args.Get("gt", "");
  if (args.Has("truth-ratio") &&
      (!ParseNumber(args.Get("truth-ratio"), &d.degenerate_ratio) || d.degenerate_ratio <= 0.0))
    return Fail(kEval, "--truth-ratio '" + args.Get("truth-ratio") + "' is not a positive number");
  StatusOr<DegeneracyEvalResult> r = EvaluateDegeneracyFiles(d);
  if (!r.ok()) return Fail(kEval, r.status());
  for (const std::string& w : r->scores.warnings)
    std::fprintf(stderr, "rvlio %s: warning: %s\n", kEval, w.c_str());
  if (args.Has("json"))
    std::cout << JsonText(DegeneracyEvalJson(*r), -1) << "\n";
  else
    PrintDegeneracyTable(*r);
  return 0;
}

int EvalMap(const Args& args) {
  if (args.Has("gt") || args.Has("est"))
    return Fail(kEval, "--map/--ref-map (map mode) cannot be combined with --gt/--est");
  if (!args.Has("map") || !args.Has("ref-map"))
    return Fail(kEval, "map mode needs both --map FILE and --ref-map FILE");
  MapEvalOptions options;
  if (std::string error = ReadMapOptions(args, &options); !error.empty()) return Fail(kEval, error);
  StatusOr<MapEvalResult> r = Status::Internal("not evaluated");
  {
    ProgressLine line(true);  // ends its line before the table is printed
    const auto t0 = std::chrono::steady_clock::now();
    r = EvaluateMapFiles(args.Get("map"), args.Get("ref-map"), options, [&](double fraction) {
      const std::chrono::duration<double> wall = std::chrono::steady_clock::now() - t0;
      line.Update(wall.count(), fraction, "map eval: nearest-point searches");
    });
  }
  if (!r.ok()) return Fail(kEval, r.status());
  if (args.Has("json"))
    std::cout << JsonText(MapEvalJson(*r), -1) << "\n";
  else
    PrintMapTable(*r, args.Get("map"), args.Get("ref-map"));
  return 0;
}

}  // namespace

int CmdEval(int argc, char** argv) {
  const CommandSpec spec = EvalSpec();
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  if (args.Has("degeneracy") || args.Has("truth")) {
    if (!args.Has("degeneracy")) return Fail(kEval, "--truth SIM_DIR needs --degeneracy RUN_DIR");
    return EvalDegeneracy(args);
  }
  if (args.Has("map") || args.Has("ref-map")) return EvalMap(args);
  for (const char* required : {"gt", "est"})  // trajectory mode
    if (!args.Has(required))
      return Fail(kEval, std::string("missing required option --") + required +
                             " (or --map FILE --ref-map FILE for a map)");
  EvalOptions options;
  if (std::string error = ReadOptions(args, &options); !error.empty()) return Fail(kEval, error);

  StatusOr<EvalResult> result = EvaluateFiles(args.Get("gt"), args.Get("est"), options);
  if (!result.ok()) return Fail(kEval, result.status());

  for (const std::string& w : result->warnings)
    std::fprintf(stderr, "rvlio %s: warning: %s\n", kEval, w.c_str());
  if (args.Has("json"))
    PrintJson(*result);
  else
    PrintTable(*result, options);
  return 0;
}

}  // namespace rvlio::cli

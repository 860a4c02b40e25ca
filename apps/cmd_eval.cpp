// rvlio eval: ATE/RPE of an estimated trajectory against ground truth with the
// definitions of evo (docs/design.md section 8). Argument parsing and output only;
// EvaluateFiles and EvalJson (rvlio/api.h) do the work.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include "commands.h"
#include "rvlio/io/summary_json.h"
#include "common_options.h"
#include "rvlio/api.h"

namespace rvlio::cli {
namespace {

constexpr const char* kName = "eval";

CommandSpec EvalSpec() {
  return {
      kName,
      "ATE/RPE of an estimated trajectory against ground truth, with the definitions of the evo\n"
      "tool. Trajectories are TUM (t x y z qx qy qz qw) or KITTI (3x4 rows, assumed 10 Hz)\n"
      "files, detected by their column count. Exit status 2 on bad input.",
      {{"gt", "FILE", "reference trajectory", true, false},
       {"est", "FILE", "estimated trajectory", true, false},
       {"align", "MODE", "se3 | sim3 | origin | none (default se3)", false, false},
       {"rpe-delta", "N", "RPE step (default 1)", false, false},
       {"rpe-unit", "UNIT", "frames | meters (default frames)", false, false},
       {"max-dt", "S", "association tolerance in seconds (default 0.01)", false, false},
       {"json", "", "print one JSON object instead of the table", false, false}}};
}

bool ParseNumber(const std::string& text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return !text.empty() && *end == '\0' && std::isfinite(*value);
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

}  // namespace

int CmdEval(int argc, char** argv) {
  const CommandSpec spec = EvalSpec();
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  EvalOptions options;
  if (std::string error = ReadOptions(args, &options); !error.empty()) return Fail(kName, error);

  StatusOr<EvalResult> result = EvaluateFiles(args.Get("gt"), args.Get("est"), options);
  if (!result.ok()) return Fail(kName, result.status().message(), result.status().exit_code());

  for (const std::string& w : result->warnings)
    std::fprintf(stderr, "rvlio %s: warning: %s\n", kName, w.c_str());
  if (args.Has("json"))
    PrintJson(*result);
  else
    PrintTable(*result, options);
  return 0;
}

}  // namespace rvlio::cli

// EvaluateFiles and EvalJson (rvlio/api.h): `rvlio eval` without its
// argument parsing and table.
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "rvlio/api.h"
#include "rvlio/io/trajectory_io.h"

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

}  // namespace rvlio

// EvaluateFiles and EvalJson (rvlio/api.h): `rvlio eval` without its
// argument parsing and table.
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "rvlio/api.h"
#include "rvlio/io/point_cloud_file.h"
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

nlohmann::json DistanceJson(const ErrorStats& s) {
  return {{"count", s.count},        {"mean", Num(s.mean)}, {"rms", Num(s.rmse)},
          {"median", Num(s.median)}, {"p95", Num(s.p95)},   {"max", Num(s.max)}};
}

nlohmann::json VectorJson(const Eigen::Vector3d& v) { return {Num(v.x()), Num(v.y()), Num(v.z())}; }

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
                                         const MapEvalOptions& options) {
  const PointCloudReadOptions xyz_only{false};
  StatusOr<PointCloudFile> map = ReadPointCloud(map_path, xyz_only);
  if (!map.ok()) return map.status();
  StatusOr<PointCloudFile> ref = ReadPointCloud(ref_path, xyz_only);
  if (!ref.ok()) return ref.status();
  StatusOr<MapEvalResult> r = EvaluateMap(map->points, ref->points, options);
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

}  // namespace rvlio

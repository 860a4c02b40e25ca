// rvlio.evaluate: the evaluation of `rvlio eval` (eval/evaluate.h), evo's
// definitions of APE and RPE; rvlio.evaluate_map: `rvlio eval --map`
// (eval/map_metrics.h); rvlio.evaluate_degeneracy: `rvlio eval --degeneracy`
// (eval/degeneracy.h); rvlio.read_map: a map.pcd with its fields.
#include "eval_py.h"

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <cmath>

#include "rvlio/api.h"
#include "rvlio/api/result_json.h"
#include "rvlio/eval/evaluate.h"
#include "rvlio/eval/map_metrics.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/formats/trajectory_io.h"
#include "odometry_py.h"  // PointsArray

namespace rvlio::python {
namespace {

// A TUM file (or KITTI, detected as `rvlio eval` does) or an (N, 8) array
// [t_s x y z qx qy qz qw].
Trajectory TrajectoryArg(const py::handle& value, const char* what) {
  if (py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__")) {
    const std::string path = PathText(value);
    RequireExisting(path, std::string(what) + " trajectory");
    return Take(ReadTrajectory(path));
  }
  const auto a = py::array_t<double, py::array::forcecast>::ensure(value);
  if (!a || a.ndim() != 2 || a.shape(1) != 8)
    ValueError(std::string(what) +
               " must be a TUM file path or an (N, 8) array [t_s, x, y, z, qx, qy, qz, qw]");
  const auto r = a.unchecked<2>();
  Trajectory t(static_cast<size_t>(r.shape(0)));
  for (py::ssize_t i = 0; i < r.shape(0); ++i) {
    for (int k = 0; k < 8; ++k)
      if (!std::isfinite(r(i, k)))
        ValueError(std::string(what) + " row " + std::to_string(i) + " is not finite");
    StampedPose& p = t[static_cast<size_t>(i)];
    p.t_ns = static_cast<TimeNs>(std::llround(r(i, 0) * 1e9));
    p.p_world_imu = {r(i, 1), r(i, 2), r(i, 3)};
    p.q_world_imu = Eigen::Quaterniond(r(i, 7), r(i, 4), r(i, 5), r(i, 6)).normalized();
  }
  bool earlier = false;  // the order the file readers enforce
  if (const size_t i = FirstStampOrderViolation(t, &earlier); i > 0)
    ValueError(std::string(what) + " row " + std::to_string(i) +
               (earlier ? ": time stamp earlier than the previous row's; stamps must not decrease"
                        : ": time stamp is the third in a row; stamps must increase"));
  return t;
}

py::dict StatsDict(const ErrorStats& s) {
  py::dict d;
  d["rmse"] = s.rmse;
  d["mean"] = s.mean;
  d["median"] = s.median;
  d["std"] = s.std;
  d["min"] = s.min;
  d["max"] = s.max;
  d["count"] = s.count;
  return d;
}

py::dict ResultDict(const EvalResult& r) {
  py::dict d;
  d["matched"] = r.matched;
  d["align"] = AlignModeName(r.align);
  d["scale"] = r.T_ref_est.scale;
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = r.T_ref_est.scale * r.T_ref_est.R_ref_est;
  T.topRightCorner<3, 1>() = r.T_ref_est.t_ref_est;
  d["T_ref_est"] = py::cast(T);
  d["ape"] = StatsDict(r.ape_m);
  d["ape_rot_deg"] = StatsDict(r.ape_rot_deg);
  py::dict rpe = StatsDict(r.rpe.trans_m);
  rpe["pairs"] = r.rpe.pairs;
  d["rpe"] = rpe;
  d["rpe_rot_deg"] = StatsDict(r.rpe.rot_deg);
  d["end_point_error"] = r.end_point_error_m;
  py::dict along;
  along["axis"] = py::cast(Eigen::Vector3d(r.along_axis.axis));
  along["rmse"] = r.along_axis.rmse_m;
  along["max"] = r.along_axis.max_abs_m;
  d["along_axis"] = along;
  d["warnings"] = py::cast(r.warnings);
  return d;
}

// A PCD/PLY path or an (N, 3) array of x y z (m).
std::vector<Eigen::Vector3d> CloudArg(const py::handle& value, const char* what) {
  if (py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__")) {
    const std::string path = PathText(value);
    RequireExisting(path, std::string(what) + " point cloud");
    return Take(ReadPointCloud(path, PointCloudReadOptions{false})).points;
  }
  const auto a = py::array_t<double, py::array::forcecast>::ensure(value);
  if (!a || a.ndim() != 2 || a.shape(1) != 3)
    ValueError(std::string(what) + " must be a PCD/PLY file path or an (N, 3) array [x, y, z]");
  const auto r = a.unchecked<2>();
  std::vector<Eigen::Vector3d> points(static_cast<size_t>(r.shape(0)));
  for (py::ssize_t i = 0; i < r.shape(0); ++i) points[i] = {r(i, 0), r(i, 1), r(i, 2)};
  return points;
}

py::dict DistanceDict(const ErrorStats& s) {
  py::dict d;
  d["count"] = s.count;
  d["mean"] = s.mean;
  d["rms"] = s.rmse;
  d["median"] = s.median;
  d["p95"] = s.p95;
  d["max"] = s.max;
  return d;
}

// The keys of `rvlio eval --map --json`, unrounded; the profile as columns
// (numpy arrays) instead of a list of rows.
py::dict MapResultDict(const MapEvalResult& r) {
  py::dict d;
  d["map_points"] = r.map_points;
  d["ref_points"] = r.ref_points;
  d["max_distance"] = r.max_distance_m;
  d["inliers"] = r.inliers;
  d["no_plane"] = r.no_plane;
  d["outlier_fraction"] = r.outlier_fraction;
  d["accuracy"] = DistanceDict(r.accuracy);
  d["nearest"] = DistanceDict(r.nearest);
  d["completeness"] = r.completeness;
  d["chamfer"] = r.chamfer_m;
  py::dict axis;
  axis["origin"] = py::cast(r.axis_origin);
  axis["direction"] = py::cast(r.axis_direction);
  d["axis"] = axis;
  const size_t n = r.profile.size();
  py::array_t<double> chainage(n), rms(n), median(n), p95(n), completeness(n);
  py::array_t<int64_t> map_points(n), map_with_plane(n), ref_points(n);
  for (size_t i = 0; i < n; ++i) {
    const MapProfileBin& b = r.profile[i];
    chainage.mutable_at(i) = b.chainage_m;
    rms.mutable_at(i) = b.rms_m;
    median.mutable_at(i) = b.median_m;
    p95.mutable_at(i) = b.p95_m;
    completeness.mutable_at(i) = b.completeness;
    map_points.mutable_at(i) = static_cast<int64_t>(b.map_points);
    map_with_plane.mutable_at(i) = static_cast<int64_t>(b.map_with_plane);
    ref_points.mutable_at(i) = static_cast<int64_t>(b.ref_points);
  }
  py::dict profile;
  profile["chainage"] = chainage;
  profile["map_points"] = map_points;
  profile["map_with_plane"] = map_with_plane;
  profile["rms"] = rms;
  profile["median"] = median;
  profile["p95"] = p95;
  profile["ref_points"] = ref_points;
  profile["completeness"] = completeness;
  d["profile"] = profile;
  return d;
}

// A PCD's points and every scalar field, read in chunks (PointCloudStream).
struct MapRead {
  std::vector<PointCloudStreamField> fields;
  std::vector<Eigen::Vector3d> xyz;
  std::vector<std::vector<double>> values;  // per field, one per point
};

StatusOr<MapRead> ReadMapFields(const std::string& path) {
  PointCloudStream stream;
  if (Status s = stream.Open(path); !s.ok()) return s;
  MapRead out;
  out.fields = stream.fields();
  out.values.resize(out.fields.size());
  PointCloudChunk chunk;
  for (;;) {
    StatusOr<size_t> n = stream.Read(size_t{1} << 16, &chunk);
    if (!n.ok()) return n.status();
    if (*n == 0) return out;
    out.xyz.insert(out.xyz.end(), chunk.points.begin(), chunk.points.begin() + *n);
    for (size_t k = 0; k < out.fields.size(); ++k)
      out.values[k].insert(out.values[k].end(), chunk.fields[k].begin(), chunk.fields[k].begin() + *n);
  }
}

template <typename T>
py::array ColumnOf(const std::vector<double>& values) {
  py::array_t<T> a(static_cast<py::ssize_t>(values.size()));
  T* out = a.mutable_data();
  for (size_t i = 0; i < values.size(); ++i) out[i] = static_cast<T>(values[i]);
  return a;
}

// One field as an array of the field's own type (F4 float32, F8 float64,
// U2 uint16, ...).
py::array FieldArray(const PointCloudStreamField& f, const std::vector<double>& values) {
  if (f.type == 'F') return f.size == 8 ? ColumnOf<double>(values) : ColumnOf<float>(values);
  const bool is_signed = f.type == 'I';
  switch (f.size) {
    case 1: return is_signed ? ColumnOf<int8_t>(values) : ColumnOf<uint8_t>(values);
    case 2: return is_signed ? ColumnOf<int16_t>(values) : ColumnOf<uint16_t>(values);
    case 4: return is_signed ? ColumnOf<int32_t>(values) : ColumnOf<uint32_t>(values);
    default: return is_signed ? ColumnOf<int64_t>(values) : ColumnOf<uint64_t>(values);
  }
}

py::dict ReadMap(const py::handle& path_obj) {
  const std::string path = PathText(path_obj);
  RequireExisting(path, "map");
  StatusOr<MapRead> read = Status::Internal("not read");
  {
    py::gil_scoped_release release;
    read = ReadMapFields(path);
  }
  const MapRead r = Take(std::move(read));
  py::dict d;
  d["xyz"] = PointsArray(r.xyz);
  for (size_t k = 0; k < r.fields.size(); ++k)
    d[py::str(r.fields[k].name)] = FieldArray(r.fields[k], r.values[k]);
  return d;
}

}  // namespace

void BindEval(py::module_& m) {
  m.def("read_map", &ReadMap, py::arg("path"),
        "A map.pcd (PCD DATA ascii or binary, any size: read in chunks) as a dict of numpy "
        "arrays: xyz (N, 3) float64 in metres, then every other field of the file under its "
        "own name in its own type: intensity float32, time float64 (UNIX seconds), ring "
        "uint16, scan_index uint32, deviation_m float32 (NaN: no surface), as far as the "
        "map has them (docs/outputs.md \"map.pcd\"). ValueError for a missing file, a "
        "PLY or binary_compressed PCD, a malformed or truncated one.");

  m.def(
      "evaluate_map",
      [](const py::handle& map, const py::handle& ref, double max_distance, double profile_step,
         int num_neighbors, double search_radius, int threads) {
        MapEvalOptions options;
        options.max_distance = max_distance;
        options.profile_step = profile_step;
        options.surface.num_neighbors = num_neighbors;
        options.surface.search_radius = search_radius;
        options.threads = threads;
        Check(options.Validate());
        const std::vector<Eigen::Vector3d> map_points = CloudArg(map, "map");
        const std::vector<Eigen::Vector3d> ref_points = CloudArg(ref, "ref");
        StatusOr<MapEvalResult> result = Status::Internal("not evaluated");
        {
          py::gil_scoped_release release;
          result = EvaluateMap(map_points, ref_points, options);
        }
        return MapResultDict(Take(std::move(result)));
      },
      py::arg("map"), py::arg("ref"), py::kw_only(), py::arg("max_distance") = 0.1,
      py::arg("profile_step") = 1.0, py::arg("num_neighbors") = 8, py::arg("search_radius") = 0.5,
      py::arg("threads") = 1,
      "Accuracy of a map against a reference cloud (`rvlio eval --map --json`, unrounded; "
      "docs/map_eval.md). map/ref: PCD or PLY paths or (N, 3) arrays [x, y, z] in metres, one "
      "frame. Points are searched in single precision. Returns a dict: accuracy and nearest "
      "{count, mean, rms, median, p95, max} (m), completeness, chamfer, outlier_fraction, "
      "inliers, no_plane, axis and profile (columns as arrays).");

  m.def(
      "evaluate",
      [](const py::handle& gt, const py::handle& est, const std::string& align, double max_dt,
         double rpe_delta, const std::string& rpe_unit) {
        EvalOptions options;
        options.align = align;
        options.max_dt = max_dt;
        options.rpe_delta = rpe_delta;
        options.rpe_unit = rpe_unit;
        Check(options.Validate());
        const Trajectory ref = TrajectoryArg(gt, "gt");
        const Trajectory estimate = TrajectoryArg(est, "est");
        StatusOr<EvalResult> result = Status::Internal("not evaluated");
        {
          py::gil_scoped_release release;
          result = Evaluate(ref, estimate, options);
        }
        return ResultDict(Take(std::move(result)));
      },
      py::arg("gt"), py::arg("est"), py::arg("align") = "se3", py::arg("max_dt") = 0.01,
      py::arg("rpe_delta") = 1.0, py::arg("rpe_unit") = "frames",
      "APE and RPE of `est` against `gt` with evo's definitions (`rvlio eval --json`, "
      "unrounded). gt/est: TUM (or KITTI) file paths or (N, 8) arrays [t_s x y z qx qy qz qw]. "
      "align: se3 | sim3 | origin | none; rpe_unit: frames | meters.");

  m.def(
      "evaluate_degeneracy",
      [](const py::handle& run_dir, const py::handle& truth_dir, const py::object& gt,
         double truth_ratio, const std::string& align, double max_dt) {
        DegeneracyEvalArgs args;
        args.run_dir = PathText(run_dir);
        args.truth_dir = PathText(truth_dir);
        if (!gt.is_none()) args.gt_path = PathText(gt);
        args.degenerate_ratio = truth_ratio;
        args.eval.align = align;
        args.eval.max_dt = max_dt;
        Check(args.eval.Validate());
        StatusOr<DegeneracyEvalResult> result = Status::Internal("not evaluated");
        {
          py::gil_scoped_release release;
          result = EvaluateDegeneracyFiles(args);
        }
        return ToPython(DegeneracyEvalJson(Take(std::move(result))));
      },
      py::arg("run_dir"), py::arg("truth_dir"), py::kw_only(), py::arg("gt") = py::none(),
      py::arg("truth_ratio") = 0.0, py::arg("align") = "se3", py::arg("max_dt") = 0.01,
      "A run's per-scan degeneracy detection (run_dir/scans.csv, trajectory.tum) against the "
      "simulator's true localizability (truth_dir/localizability.csv and its *_gt.tum, or gt): "
      "the dict of `rvlio eval --degeneracy --json` (docs/degeneracy_truth.md). truth_ratio > "
      "0 re-thresholds the truth (lambda_min / lambda_max below it is degenerate).");
}

}  // namespace rvlio::python

// rvlio.evaluate: the evaluation of `rvlio eval` (eval/evaluate.h), evo's
// definitions of APE and RPE.
#include "eval_py.h"

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <cmath>

#include "rvlio/eval/evaluate.h"
#include "rvlio/io/trajectory_io.h"

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

}  // namespace

void BindEval(py::module_& m) {
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
}

}  // namespace rvlio::python

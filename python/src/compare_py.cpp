// rvlio.compare: `rvlio compare` through the library (rvlio/experiments/
// compare.h), with the GIL released and Ctrl-C as KeyboardInterrupt.
#include "compare_py.h"

#include <pybind11/stl.h>

#include <cmath>
#include <string>
#include <vector>

#include "odometry_py.h"
#include "rvlio/experiments/compare.h"

namespace rvlio::python {
namespace {

namespace ex = experiments;

// None, one path, or a list of paths.
std::vector<std::string> PathList(const py::handle& paths) {
  if (paths.is_none()) return {};
  if (py::isinstance<py::str>(paths) || py::hasattr(paths, "__fspath__")) return {PathText(paths)};
  std::vector<std::string> out;
  for (const py::handle& p : paths) out.push_back(PathText(p));
  return out;
}

py::object Number(double v) { return std::isfinite(v) ? py::object(py::float_(v)) : py::none(); }

// One row of compare.csv as a dict, with the estimate (N, 8) as the TUM file holds it.
py::dict RowDict(const ex::CompareRow& r) {
  py::dict d;
  d["variant"] = r.name;
  d["label"] = r.label;
  d["status"] = r.StatusName();
  d["exit_code"] = r.exit_code;
  d["init"] = r.init;
  d["scans"] = r.scans;
  d["error"] = !r.run_error.ok() ? r.run_error.message() : r.eval_error;
  d["wall_s"] = r.wall_s;
  const bool m = r.measured();
  d["ate_rmse_m"] = m ? Number(r.eval->ape_m.rmse) : py::none();
  d["rpe_rmse_m"] = m ? Number(r.eval->rpe.trans_m.rmse) : py::none();
  d["axis_max_m"] = m ? Number(r.eval->along_axis.max_abs_m) : py::none();
  d["end_point_m"] = m ? Number(r.eval->end_point_error_m) : py::none();
  d["ms_per_scan"] = m ? Number(r.ms_per_scan) : py::none();
  d["real_time_factor"] = m ? Number(r.real_time_factor) : py::none();
  d["map_rms_m"] = r.map_eval ? Number(r.map_eval->accuracy.rmse) : py::none();
  d["map_completeness"] = r.map_eval ? Number(r.map_eval->completeness) : py::none();
  d["trajectory"] = TrajectoryArray(r.trajectory);
  return d;
}

py::list Compare(const py::handle& bag, const py::handle& gt, const py::handle& out,
                 const py::handle& config, const std::vector<std::string>& set,
                 const py::handle& ref_map, bool refine, double start, double duration) {
  ex::CompareRequest req;
  req.bag = PathText(bag);
  RequireExisting(req.bag, "recording");
  req.gt = PathText(gt);
  req.out_dir = PathText(out);
  if (req.out_dir.empty()) ValueError("out is an empty path: compare writes each run's folder");
  req.config_files = PathList(config);
  req.overrides = set;
  if (!ref_map.is_none()) req.ref_map = PathText(ref_map);
  req.refine = refine;
  req.window.start_s = start;
  req.window.duration_s = duration;
  SignalCheck signals;
  req.stop = [&signals] {
    return signals.Stop() ? std::string("KeyboardInterrupt") : std::string();
  };
  StatusOr<ex::CompareResult> result = [&] {
    py::gil_scoped_release release;
    return ex::RunCompare(req);
  }();
  signals.Rethrow();
  const ex::CompareResult r = Take(std::move(result));
  Check(ex::WriteCompareTables(req, r));
  Check(ex::WriteCompareJson(req, r, ex::ComparePlots()));
  py::list rows;
  for (const ex::CompareRow& row : r.rows) rows.append(RowDict(row));
  return rows;
}

}  // namespace

void BindCompare(py::module_& m) {
  m.def("compare", &Compare, py::arg("bag"), py::arg("gt"), py::arg("out"), py::kw_only(),
        py::arg("config") = py::none(), py::arg("set") = std::vector<std::string>(),
        py::arg("ref_map") = py::none(), py::arg("refine") = true, py::arg("start") = 0.0,
        py::arg("duration") = 0.0,
        "`rvlio compare` without plots: the standard variants (IESKF and smoother, RV off and "
        "on), then refine from the best; each run writes OUT/<variant>/, and OUT/compare.csv, "
        ".md and .json are written. config: YAML paths; set: key=value overrides. Returns one "
        "dict per row of compare.csv (None for a figure that is not there) with its "
        "'trajectory' (N, 8: t x y z qx qy qz qw, as trajectory.tum holds it). Bad input "
        "raises ValueError before any run; Ctrl-C raises KeyboardInterrupt.");
}

}  // namespace rvlio::python

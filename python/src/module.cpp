// The compiled part of the Python package rvlio (python/rvlio/__init__.py
// re-exports it).
#include "bag_py.h"
#include "common.h"
#include "compare_py.h"
#include "config_py.h"
#include "eval_py.h"
#include "odometry_py.h"
#include "run_py.h"
#include "rvlio/version.h"

PYBIND11_MODULE(_rvlio, m) {
  m.doc() = "rvlio: LiDAR-inertial odometry with reinforced vectors (RV-LIO)";
  m.attr("__version__") = RVLIO_VERSION;
  // Size of one point inside the library (the copy add_scan makes), bytes.
  m.attr("LIDAR_POINT_BYTES") = sizeof(rvlio::LidarPoint);
  rvlio::python::BindConfig(m);
  rvlio::python::BindOdometry(m);
  rvlio::python::BindBag(m);
  rvlio::python::BindEval(m);
  rvlio::python::BindRun(m);
  rvlio::python::BindCompare(m);
}

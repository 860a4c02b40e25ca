// rvlio.Odometry: IMU samples and timed scans in, one ScanResult per scan out
// (odometry/odometry.h), for either backend.
#include "odometry_py.h"

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <memory>

#include "config_py.h"
#include "rvlio/outputs/run_outputs.h"
#include "rvlio/odometry/odometry.h"

namespace rvlio::python {
namespace {

std::string ShapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string Describe(const py::array& a) {
  return "shape " + ShapeText(a) + " dtype " + py::str(a.dtype()).cast<std::string>();
}

py::array AsArray(const py::handle& value, const char* what) {
  if (!py::isinstance<py::array>(value))
    throw py::type_error(std::string(what) + " must be a numpy array, got " +
                         py::str(py::type::of(value)).cast<std::string>());
  return py::reinterpret_borrow<py::array>(value);
}

// Copies the points and their time offsets straight from the arrays into
// scan->points: the only copy of the points on the way in. Points must be
// (N, 3) float32/float64, times (N,) integer nanoseconds from t_ns.
template <typename P, typename T>
void FillPoints(const py::array& points, const py::array& times, const py::handle& intensity,
                TimeNs t_ns, Scan* scan) {
  const auto p = points.unchecked<P, 2>();
  const auto t = times.unchecked<T, 1>();
  const py::ssize_t n = p.shape(0);
  py::array_t<float, py::array::forcecast> in;
  if (!intensity.is_none()) {
    in = py::array_t<float, py::array::forcecast>::ensure(intensity);
    if (!in || in.ndim() != 1 || in.shape(0) != n)
      ValueError("intensity must be an (N,) array with one value per point (N = " +
                 std::to_string(n) + ")");
  }
  scan->points.resize(static_cast<size_t>(n));
  TimeNs t_min = std::numeric_limits<TimeNs>::max(), t_max = std::numeric_limits<TimeNs>::min();
  for (py::ssize_t i = 0; i < n; ++i) {
    LidarPoint& q = scan->points[static_cast<size_t>(i)];
    q.p_lidar = Eigen::Vector3f(static_cast<float>(p(i, 0)), static_cast<float>(p(i, 1)),
                                static_cast<float>(p(i, 2)));
    if (!q.p_lidar.allFinite())
      ValueError("points[" + std::to_string(i) + "] is not finite (NaN or Inf): drop such points "
                 "before add_scan");
    q.t_ns = t_ns + static_cast<TimeNs>(t(i));
    t_min = std::min(t_min, q.t_ns);
    t_max = std::max(t_max, q.t_ns);
  }
  if (in) {
    const auto r = in.unchecked<1>();
    for (py::ssize_t i = 0; i < n; ++i) scan->points[static_cast<size_t>(i)].intensity = r(i);
    scan->has_intensity = true;
  }
  scan->t_start_ns = t_min;
  scan->t_end_ns = t_max;
}

template <typename P>
void FillPointsTyped(const py::array& points, const py::array& times, const py::handle& intensity,
                     TimeNs t_ns, Scan* scan) {
  const char kind = times.dtype().kind();
  const auto size = times.itemsize();
  if (kind == 'i' && size == 8) return FillPoints<P, int64_t>(points, times, intensity, t_ns, scan);
  if (kind == 'i' && size == 4) return FillPoints<P, int32_t>(points, times, intensity, t_ns, scan);
  if (kind == 'u' && size == 4) return FillPoints<P, uint32_t>(points, times, intensity, t_ns, scan);
  if (kind == 'u' && size == 8) return FillPoints<P, uint64_t>(points, times, intensity, t_ns, scan);
  ValueError("times must be integer nanoseconds (int64, int32, uint32 or uint64), got dtype " +
             py::str(times.dtype()).cast<std::string>());
}

}  // namespace

Scan ScanFromArrays(TimeNs t_ns, const py::handle& points_obj, const py::handle& times_obj,
                    const py::handle& intensity) {
  const py::array points = AsArray(points_obj, "points");
  const py::array times = AsArray(times_obj, "times");
  if (points.ndim() != 2 || points.shape(1) != 3)
    ValueError("points must be an (N, 3) array, got " + Describe(points));
  if (times.ndim() != 1 || times.shape(0) != points.shape(0))
    ValueError("times must be an (N,) array with one offset per point (N = " +
               std::to_string(points.shape(0)) + "), got " + Describe(times));
  if (points.shape(0) == 0) ValueError("the scan has no point");
  Scan scan;
  const char kind = points.dtype().kind();
  if (kind == 'f' && points.itemsize() == 4)
    FillPointsTyped<float>(points, times, intensity, t_ns, &scan);
  else if (kind == 'f' && points.itemsize() == 8)
    FillPointsTyped<double>(points, times, intensity, t_ns, &scan);
  else
    ValueError("points must be float32 or float64, got dtype " +
               py::str(points.dtype()).cast<std::string>());
  return scan;
}

OdometrySession::OdometrySession(const Config& config)
    : odometry_(Take(Odometry::Create(config.options))) {}

void OdometrySession::AddImu(const ImuSample& imu) {
  if (!imu.gyro_imu.allFinite() || !imu.acc_imu.allFinite())
    ValueError("IMU sample at t_ns = " + std::to_string(imu.t_ns) + " is not finite (NaN or Inf)");
  if (has_imu_ && imu.t_ns <= last_imu_ns_)
    ValueError("IMU times must increase: t_ns = " + std::to_string(imu.t_ns) +
               " is not after the previous sample's " + std::to_string(last_imu_ns_));
  has_imu_ = true;
  last_imu_ns_ = imu.t_ns;
  odometry_->AddImu(imu);
}

void OdometrySession::AddImuArrays(const py::handle& t_obj, const py::handle& gyro_obj,
                                   const py::handle& acc_obj) {
  const py::array t = AsArray(t_obj, "t_ns");
  if (t.ndim() != 1 || t.dtype().kind() != 'i' || t.itemsize() != 8)
    ValueError("t_ns must be an (M,) int64 array of nanoseconds, got " + Describe(t));
  const py::ssize_t n = t.shape(0);
  auto vectors = [n](const py::handle& obj, const char* what) {
    const py::array a = AsArray(obj, what);
    if (a.ndim() != 2 || a.shape(0) != n || a.shape(1) != 3 || a.dtype().kind() != 'f')
      ValueError(std::string(what) + " must be an (M, 3) float array with M = " +
                 std::to_string(n) + ", got " + Describe(a));
    return py::array_t<double, py::array::forcecast>::ensure(a);
  };
  const auto g = vectors(gyro_obj, "gyro"), a = vectors(acc_obj, "acc");
  const auto tv = t.unchecked<int64_t, 1>();
  const auto gv = g.unchecked<2>(), av = a.unchecked<2>();
  for (py::ssize_t i = 0; i < n; ++i) {
    ImuSample s;
    s.t_ns = tv(i);
    s.gyro_imu = {gv(i, 0), gv(i, 1), gv(i, 2)};
    s.acc_imu = {av(i, 0), av(i, 1), av(i, 2)};
    AddImu(s);
  }
}

void OdometrySession::AddScan(Scan scan) {
  if (has_scan_ && scan.t_end_ns <= last_scan_end_ns_)
    ValueError("scan times must increase: this scan ends at t_ns = " +
               std::to_string(scan.t_end_ns) + ", not after the previous scan's end " +
               std::to_string(last_scan_end_ns_));
  has_scan_ = true;
  last_scan_end_ns_ = scan.t_end_ns;
  odometry_->AddScan(std::move(scan));
}

std::vector<ScanResult> OdometrySession::Poll() {
  std::vector<ScanResult> out;
  py::gil_scoped_release release;
  odometry_->Poll(&out);
  return out;
}

std::vector<ScanResult> OdometrySession::Finish() {
  std::vector<ScanResult> out;
  py::gil_scoped_release release;
  odometry_->Finish(&out);
  return out;
}

py::array_t<double> PointsArray(const std::vector<Eigen::Vector3d>& p) {
  py::array_t<double> a({static_cast<py::ssize_t>(p.size()), py::ssize_t{3}});
  auto w = a.mutable_unchecked<2>();
  for (size_t i = 0; i < p.size(); ++i)
    for (int k = 0; k < 3; ++k) w(static_cast<py::ssize_t>(i), k) = p[i][k];
  return a;
}

py::array_t<double> TrajectoryArray(const Trajectory& trajectory) {
  py::array_t<double> a({static_cast<py::ssize_t>(trajectory.size()), py::ssize_t{8}});
  auto w = a.mutable_unchecked<2>();
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const StampedPose& p = trajectory[i];
    const double row[8] = {NsToSeconds(p.t_ns), p.p_world_imu.x(), p.p_world_imu.y(),
                           p.p_world_imu.z(),   p.q_world_imu.x(), p.q_world_imu.y(),
                           p.q_world_imu.z(),   p.q_world_imu.w()};
    for (int k = 0; k < 8; ++k) w(static_cast<py::ssize_t>(i), k) = row[k];
  }
  return a;
}

py::array_t<double> TumArray(const std::vector<ScanResult>& results) {
  return TrajectoryArray(ToTrajectory(results));
}

namespace {

py::dict StatsDict(const OdometryStats& s) {
  py::dict d;
  d["scans_received"] = s.scans_received;
  d["scans_processed"] = s.scans_processed;
  d["scans_before_imu"] = s.scans_before_imu;
  d["scans_too_few_points"] = s.scans_too_few_points;
  d["predict_only"] = s.predict_only;
  d["diverged_resets"] = s.diverged_resets;
  d["imu_gaps_over_scan"] = s.imu_gaps_over_scan;
  d["initialized"] = s.initialized;
  d["started_moving"] = s.started_moving;
  d["scans_out_of_order"] = s.scans_out_of_order;
  d["scans_stamp_ahead"] = s.scans_stamp_ahead;
  d["imu_non_finite"] = s.imu_non_finite;
  return d;
}

void BindResults(py::module_& m) {
  py::class_<RvReport>(m, "RvReport", "What the RV pass did on one scan (rv/rv.h).")
      .def_readonly("active", &RvReport::active)
      .def_readonly("n_alpha", &RvReport::n_alpha)
      .def_readonly("num_constraints", &RvReport::num_constraints)
      .def_readonly("num_usable", &RvReport::num_usable)
      .def_readonly("num_scv", &RvReport::num_scv)
      .def_readonly("num_coplanar", &RvReport::num_coplanar)
      .def_readonly("num_reinforced", &RvReport::num_reinforced)
      .def_readonly("num_repaired", &RvReport::num_repaired)
      .def_readonly("K", &RvReport::K)
      .def_readonly("iterations", &RvReport::iterations)
      .def_readonly("coplanar_fraction", &RvReport::coplanar_fraction)
      .def_readonly("s_eigenvalues", &RvReport::s_eigenvalues)
      .def_readonly("localizability", &RvReport::localizability);

  py::class_<ScanResult>(m, "ScanResult", "The estimate after one scan (odometry/odometry.h).")
      .def_readonly("t_ns", &ScanResult::t_ns, "scan end time, ns: the output stamp")
      .def_property_readonly("t_s", [](const ScanResult& r) { return NsToSeconds(r.t_ns); })
      .def_property_readonly("position", [](const ScanResult& r) { return r.T_world_imu.t; },
                             "p_world_imu, m")
      .def_property_readonly(
          "quaternion",
          [](const ScanResult& r) {
            const Eigen::Quaterniond q = r.T_world_imu.quaternion();
            return Eigen::Vector4d(q.x(), q.y(), q.z(), q.w());
          },
          "q_world_imu as x, y, z, w")
      .def_property_readonly("T_world_imu", [](const ScanResult& r) {
                               Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
                               T.topLeftCorner<3, 3>() = r.T_world_imu.R;
                               T.topRightCorner<3, 1>() = r.T_world_imu.t;
                               return T;
                             },
                             "4x4 homogeneous pose of the IMU in the world")
      .def_readonly("velocity", &ScanResult::v_world_imu, "v_world_imu, m/s")
      .def_property_readonly("status", [](const ScanResult& r) { return ScanStatusName(r.status); })
      .def_readonly("raw_points", &ScanResult::raw_points)
      .def_readonly("downsampled_points", &ScanResult::downsampled_points)
      .def_readonly("constraints", &ScanResult::constraints)
      .def_readonly("iterations", &ScanResult::iterations)
      .def_readonly("rv", &ScanResult::rv)
      .def_readonly("ms", &ScanResult::ms, "CPU time of the scan, ms")
      .def("__repr__", [](const ScanResult& r) {
        const Eigen::Vector3d& p = r.T_world_imu.t;
        return "<rvlio.ScanResult t=" + std::to_string(NsToSeconds(r.t_ns)) + " s status=" +
               ScanStatusName(r.status) + " p=[" + std::to_string(p.x()) + ", " +
               std::to_string(p.y()) + ", " + std::to_string(p.z()) + "] rv=" +
               (r.rv.active ? "on" : "off") + ">";
      });

  m.def("tum_array", &TumArray, py::arg("results"),
        "The (N, 8) trajectory [t_s, x, y, z, qx, qy, qz, qw] of a list of ScanResult (the rows "
        "of trajectory.tum).");
}

}  // namespace

void BindOdometry(py::module_& m) {
  BindResults(m);
  py::class_<OdometrySession>(
      m, "Odometry",
      "The estimator of `rvlio run` (config backend: ieskf or smoother). Feed IMU samples and "
      "scans in time order, on the IMU clock; poll() returns the scans the IMU data covers.")
      .def(py::init([](const py::handle& config) {
             Config defaults;
             return std::make_unique<OdometrySession>(ConfigArg(config, &defaults));
           }),
           py::arg("config") = py::none())
      .def(
          "add_imu",
          [](OdometrySession& o, const py::handle& t_ns, const py::handle& gyro,
             const py::handle& acc) {
            if (py::isinstance<py::array>(t_ns) && py::reinterpret_borrow<py::array>(t_ns).ndim() == 1)
              return o.AddImuArrays(t_ns, gyro, acc);
            if (py::isinstance<py::float_>(t_ns) || !py::hasattr(t_ns, "__index__"))
              throw py::type_error("t_ns must be an integer number of nanoseconds (or an (M,) "
                                   "int64 array), got " + py::repr(t_ns).cast<std::string>());
            ImuSample s;
            s.t_ns = py::int_(py::reinterpret_borrow<py::object>(t_ns)).cast<int64_t>();
            s.gyro_imu = Vector3(gyro, "gyro");
            s.acc_imu = Vector3(acc, "acc");
            o.AddImu(s);
          },
          py::arg("t_ns"), py::arg("gyro"), py::arg("acc"),
          "One sample (t_ns int, gyro rad/s and acc m/s^2 as 3 numbers), or M samples "
          "(t_ns (M,) int64, gyro and acc (M, 3)). Times must increase; values must be finite.")
      .def(
          "add_scan",
          [](OdometrySession& o, int64_t t_ns, const py::handle& points, const py::handle& times,
             const py::handle& intensity) {
            o.AddScan(ScanFromArrays(t_ns, points, times, intensity));
          },
          py::arg("t_ns"), py::arg("points"), py::arg("times"), py::arg("intensity") = py::none(),
          "One scan: points (N, 3) float32/float64 in the LiDAR frame (m, finite), times (N,) "
          "integer ns offsets from t_ns. The scan ends at its latest point; scans must end in "
          "increasing order.")
      .def("poll", &OdometrySession::Poll,
           "Processes every scan the IMU data covers; returns their ScanResults.")
      .def("finish", &OdometrySession::Finish,
           "End of input: processes the remaining scans; returns their ScanResults.")
      .def_property_readonly("stats", [](const OdometrySession& o) { return StatsDict(o.odometry().stats()); })
      .def_property_readonly("warnings", [](const OdometrySession& o) { return o.odometry().warnings(); })
      .def(
          "map_points",
          [](const OdometrySession& o) { return PointsArray(o.odometry().MapPoints()); },
          "The map (coarse resolution), world frame, (K, 3).");
}

}  // namespace rvlio::python

// rvlio.read_bag: the IMU samples and decoded scans of a recording, as the
// commands read them (formats/sensor_stream.h: every storage kind and LiDAR layout,
// lidar.time_offset applied, range-cropped finite points).
#include "bag_py.h"

#include <pybind11/eigen.h>

#include <memory>

#include "config_py.h"
#include "rvlio/formats/sensor_stream.h"

namespace rvlio::python {
namespace {

struct ImuMessage {
  TimeNs t_ns = 0;
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();  // rad/s, IMU frame
  Eigen::Vector3d acc = Eigen::Vector3d::Zero();   // m/s^2, IMU frame
};

struct ScanMessage {
  TimeNs t_ns = 0;      // earliest point time (IMU clock)
  TimeNs t_end_ns = 0;  // latest point time: the output stamp
  py::array_t<float> points;     // (N, 3) LiDAR frame, m
  py::array_t<int64_t> times;    // (N,) ns from t_ns
  py::array_t<float> intensity;  // (N,)
};

ScanMessage ToMessage(const Scan& scan) {
  const auto n = static_cast<py::ssize_t>(scan.points.size());
  ScanMessage m;
  m.t_ns = scan.t_start_ns;
  m.t_end_ns = scan.t_end_ns;
  m.points = py::array_t<float>({n, py::ssize_t{3}});
  m.times = py::array_t<int64_t>(n);
  m.intensity = py::array_t<float>(n);
  auto p = m.points.mutable_unchecked<2>();
  auto t = m.times.mutable_unchecked<1>();
  auto in = m.intensity.mutable_unchecked<1>();
  for (py::ssize_t i = 0; i < n; ++i) {
    const LidarPoint& q = scan.points[static_cast<size_t>(i)];
    for (int k = 0; k < 3; ++k) p(i, k) = q.p_lidar[k];
    t(i) = q.t_ns - scan.t_start_ns;
    in(i) = q.intensity;
  }
  return m;
}

class BagIterator {
 public:
  explicit BagIterator(std::unique_ptr<SensorBagReader> reader) : reader_(std::move(reader)) {}

  py::object Next() {
    StatusOr<SensorMessage> m = SensorMessage::kEnd;
    {
      py::gil_scoped_release release;
      m = reader_->Next(&imu_, &scan_);
    }
    if (!m.ok()) Raise(m.status());
    if (*m == SensorMessage::kEnd) throw py::stop_iteration();
    if (*m == SensorMessage::kImu) return py::cast(ImuMessage{imu_.t_ns, imu_.gyro_imu, imu_.acc_imu});
    return py::cast(ToMessage(scan_));
  }

  py::dict Stats() const {
    const SensorReaderStats& r = reader_->stats();
    py::dict d;
    d["scans"] = r.scans;
    d["imu_samples"] = r.imu_samples;
    d["empty_scans"] = r.empty_scans;
    d["invalid_points"] = r.invalid_points;
    d["out_of_range_points"] = r.out_of_range_points;
    d["imu_invalid"] = r.imu_invalid;
    d["scans_before_first_imu"] = r.scans_before_first_imu;
    d["imu_duplicates"] = r.imu_duplicates;
    d["imu_non_monotonic"] = r.imu_non_monotonic;
    d["imu_gaps"] = r.imu_gaps;
    d["imu_max_gap_s"] = r.imu_max_gap_s;
    return d;
  }
  std::string layout() const { return reader_->lidar_layout(); }

 private:
  std::unique_ptr<SensorBagReader> reader_;
  ImuSample imu_;
  Scan scan_;
};

}  // namespace

void BindBag(py::module_& m) {
  py::class_<ImuMessage>(m, "ImuSample", "One IMU sample of a recording (IMU frame, SI units).")
      .def_readonly("t_ns", &ImuMessage::t_ns)
      .def_readonly("gyro", &ImuMessage::gyro, "rad/s")
      .def_readonly("acc", &ImuMessage::acc, "specific force, m/s^2")
      .def_property_readonly("kind", [](const ImuMessage&) { return "imu"; })
      .def("__repr__", [](const ImuMessage& s) {
        return "<rvlio.ImuSample t_ns=" + std::to_string(s.t_ns) + ">";
      });
  py::class_<ScanMessage>(m, "LidarScan",
                          "One decoded scan on the IMU clock: Odometry.add_scan(s.t_ns, s.points, "
                          "s.times) feeds it as `rvlio run` does.")
      .def_readonly("t_ns", &ScanMessage::t_ns, "earliest point time, ns")
      .def_readonly("t_end_ns", &ScanMessage::t_end_ns, "latest point time, ns (the output stamp)")
      .def_readonly("points", &ScanMessage::points, "(N, 3) float32, LiDAR frame, m")
      .def_readonly("times", &ScanMessage::times, "(N,) int64, ns from t_ns")
      .def_readonly("intensity", &ScanMessage::intensity, "(N,) float32")
      .def_property_readonly("kind", [](const ScanMessage&) { return "scan"; })
      .def("__len__", [](const ScanMessage& s) { return s.points.shape(0); })
      .def("__repr__", [](const ScanMessage& s) {
        return "<rvlio.LidarScan t_ns=" + std::to_string(s.t_ns) + " points=" +
               std::to_string(s.points.shape(0)) + ">";
      });
  py::class_<BagIterator>(m, "BagReader", "Iterator over ImuSample and LidarScan in time order.")
      .def("__iter__", [](BagIterator& it) -> BagIterator& { return it; })
      .def("__next__", &BagIterator::Next)
      .def_property_readonly("stats", &BagIterator::Stats,
                             "what the reader delivered, skipped or repaired (summary.json stats.reader)")
      .def_property_readonly("lidar_layout", &BagIterator::layout);
  m.def(
      "read_bag",
      [](const py::handle& path_obj, const py::handle& config, double start, double duration) {
        const std::string path = PathText(path_obj);
        RequireExisting(path, "recording");
        Config defaults;
        const Config& c = ConfigArg(config, &defaults);
        ReadWindow window;
        window.start_s = start;
        window.duration_s = duration;
        return BagIterator(
            Take(OpenSensorStream(path, c.options.lidar, c.options.imu, window, c.options.io)));
      },
      py::arg("path"), py::arg("config") = py::none(), py::kw_only(), py::arg("start") = 0.0,
      py::arg("duration") = 0.0,
      "Iterates over the IMU samples and scans of a recording (ROS1 .bag, ROS 2 .db3, .mcap or "
      "bag folder) with the topics, layout and time offset of `config`; start/duration (s) select "
      "a window as `rvlio run --start --duration` does.");
}

}  // namespace rvlio::python

#pragma once
#include <memory>
#include <vector>

#include "common.h"
#include "rvlio/odometry/odometry.h"

namespace rvlio::python {

struct Config;

// A scan from numpy arrays: points (N, 3) float32/float64, times (N,) integer
// ns offsets from t_ns, optional intensity (N,). ValueError for a wrong shape
// or dtype, an empty scan or a non-finite point.
Scan ScanFromArrays(TimeNs t_ns, const py::handle& points, const py::handle& times,
                    const py::handle& intensity);

// The (N, 8) TUM rows [t_s x y z qx qy qz qw] of a trajectory, of results.
py::array_t<double> TrajectoryArray(const Trajectory& trajectory);
py::array_t<double> TumArray(const std::vector<ScanResult>& results);
// (K, 3) float64 rows of points.
py::array_t<double> PointsArray(const std::vector<Eigen::Vector3d>& p);

// rvlio.Odometry: the library's Odometry plus the checks of what Python feeds
// it (finite values, increasing IMU stamps and scan ends).
class OdometrySession {
 public:
  explicit OdometrySession(const Config& config);
  void AddImu(const ImuSample& imu);
  void AddImuArrays(const py::handle& t_ns, const py::handle& gyro, const py::handle& acc);
  void AddScan(Scan scan);
  std::vector<ScanResult> Poll();
  std::vector<ScanResult> Finish();
  const Odometry& odometry() const { return *odometry_; }

 private:
  std::unique_ptr<Odometry> odometry_;
  bool has_imu_ = false, has_scan_ = false;
  TimeNs last_imu_ns_ = 0, last_scan_end_ns_ = 0;
};

void BindOdometry(py::module_& m);

}  // namespace rvlio::python

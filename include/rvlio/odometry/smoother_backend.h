#pragma once
// The sliding-window smoother as a backend of the odometry pipeline
// (odometry/pipeline.h; docs/design.md "The backends"; the window itself:
// window/window.h).
//
// Predict: IMU integration from the newest window state. Update: the scan's
// state is added with the IMU preintegration from the newest one and the
// window optimized (association rounds, RV, Ceres). Insert: the oldest state
// is marginalized when the window is full.
//
// Output: a scan's result is emitted right after its first solve, as the
// newest state of the window (online, like a filter); later refinements of
// that state inside the window are not re-emitted. The map written to
// map.pcd holds every scan at its final estimate (when marginalized, and the
// states still in the window at Finish).
//
// Working map (what association sees), smoother.map_update:
//   marginalized: a scan enters when it is marginalized, at its final
//     estimate. The first scan starts the map at its initial pose and, until
//     the window is full for the first time, each newest scan is also
//     inserted right after its first solve, so association works while the
//     window fills.
//   newest: every scan enters right after its first solve (as the IESKF
//     inserts it); window scans then also match their own points.
//
// The defaults and the measurements behind them: docs/speed.md, "The smoother's
// defaults" and "Where the smoother's time goes".
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "rvlio/imu/integrator.h"
#include "rvlio/imu/pose_history.h"
#include "rvlio/imu/static_init.h"
#include "rvlio/odometry/options.h"
#include "rvlio/odometry/pipeline.h"
#include "rvlio/window/window.h"

namespace rvlio {

class SmootherBackend {
 public:
  explicit SmootherBackend(const OdometryOptions& options);

  void Initialize(const StaticAlignment& a, const ImuSample& imu, std::deque<ImuSample>* imu_buffer);
  // Integrates the buffered IMU samples from the newest window state to the
  // scan end (the samples before the newest state are dropped first).
  Prediction Predict(std::deque<ImuSample>* imu_buffer, TimeNs t_end_ns);
  // The predicted kinematics and gravity carried into the reference frame;
  // the (still empty) window is made anew in it.
  void ChangeWorldFrame(const Pose3& T_ref_world, Prediction* prediction);
  // The first scan starts the window; every other one is added and the
  // window optimized.
  ScanStatus Update(ScanContext& scan, ScanResult* r);
  void Insert(ScanContext& scan);
  // The states still in the window enter the output map at their final estimates.
  void Finish(ScanContext& scan);

  TimeNs time_ns() const { return newest_.t_ns; }
  Pose3 T_world_imu() const { return Pose3(newest_.R_world_imu, newest_.p_world_imu); }
  Eigen::Vector3d v_world_imu() const { return newest_.v_world_imu; }
  Pose3 T_imu_lidar() const;  // the window's extrinsic (estimate or configured)
  double time_offset_s() const;
  double time_offset_std_s() const { return window_ ? window_->time_offset_std_s() : 0.0; }
  bool time_offset_at_bound() const { return window_ && window_->time_offset_at_bound(); }
  // Biases and gravity (no pose covariance: the window keeps none).
  void ReportPropagationState(ScanResult* r) const;
  bool estimates_extrinsics() const { return options_.smoother.estimate_extrinsics; }
  void CountExcitationScan() { window_->CountExcitationScan(); }
  const ExtrinsicExcitation& extrinsic_excitation() const { return window_->extrinsic_excitation(); }
  void AddReports(OdometryStats*) const {}
  std::vector<std::string> Warnings(const OdometryStats& stats) const;

  // Null before static initialization.
  const SlidingWindow* window() const { return window_.get(); }

 private:
  ScanStatus StartWindow(ScanContext& scan);
  ScanStatus UpdateWindow(ScanContext& scan, ScanResult* r);
  // State k's scan at its IMU pose of the scan time (SlidingWindow::ScanTimeImuPose).
  void InsertIntoWorkingMap(int k, const std::vector<Eigen::Vector3d>& p_lidar, WorkingMap* map);
  void MarginalizeIfFull(ScanContext& scan);
  void SetNewestFromWindow();

  OdometryOptions options_;
  WindowOptions window_options_;
  std::unique_ptr<SlidingWindow> window_;
  Pose3 T_imu_lidar_;  // configured (the prior when smoother.estimate_extrinsics)
  // The newest estimate: where the next prediction starts.
  ImuKinematics newest_;
  Eigen::Vector3d bg_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba_ = Eigen::Vector3d::Zero();
  bool window_filled_ = false;  // a state has been marginalized
  // The current scan's prediction: its IMU samples (ImuCovering) and poses.
  std::vector<ImuSample> samples_;
  ImuPoseHistory history_;
  std::vector<Eigen::Vector3d> p_world_;  // workspace
};

}  // namespace rvlio

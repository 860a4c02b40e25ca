#pragma once
// The sliding-window smoother backend of the odometry pipeline (see
// odometry.h; docs/design.md "The backends"; the window itself: window/window.h).
//
// Per scan: Predict (IMU integration from the newest window state) ->
// Downsample -> Deskew (with the predicted motion) -> add the state with the
// IMU preintegration from the newest one -> Optimize the window (association
// rounds, RV, Ceres) -> Insert -> Marginalize the oldest state when the
// window is full.
//
// Output: a scan's result is emitted right after its first solve, as the
// newest state of the window (online, like a filter); later refinements of
// that state inside the window are not re-emitted. The map written to
// map.pcd holds every scan at its final estimate (when marginalized, and the
// states still in the window at Finish()).
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
#include "rvlio/imu/noise.h"
#include "rvlio/lidar/preprocess.h"
#include "rvlio/map/output_map.h"
#include "rvlio/odometry/odometry.h"
#include "rvlio/odometry/scan_frontend.h"
#include "rvlio/window/window.h"

namespace rvlio {

class SmootherOdometry : public Odometry {
 public:
  SmootherOdometry(const OdometryOptions& options, Localization localization = {});

  void AddImu(const ImuSample& imu) override;
  void AddScan(Scan scan) override;
  void Poll(std::vector<ScanResult>* out) override;
  void Finish(std::vector<ScanResult>* out) override;

  const OdometryStats& stats() const override { return stats_; }
  const DivergenceReport& divergence() const override { return monitor_.report(); }
  std::vector<std::string> warnings() const override;
  std::vector<Eigen::Vector3d> MapPoints() const override { return output_map_.Points(); }
  MapCloud MapWithAttributes() const override { return output_map_.Cloud(); }
  const Status& status() const override { return status_; }

  // Null before static initialization.
  const SlidingWindow* window() const { return window_.get(); }

 private:
  void TryInitialize(const ImuSample& imu);
  void ProcessFrontScan(std::vector<ScanResult>* out);
  // The buffered samples from the last one at or before t0_ns to the first
  // one at or after t1_ns.
  std::vector<ImuSample> ImuCovering(TimeNs t0_ns, TimeNs t1_ns) const;
  bool HasImuGap(const std::vector<ImuSample>& samples, TimeNs t0_ns, TimeNs t1_ns) const;
  void DropImuBefore(TimeNs t_ns);
  ScanStatus StartWindow(TimeNs t_ns, const ImuKinematics& predicted);
  // Reference map: the first scan's predicted kinematics carried into the
  // reference frame (gravity and the window with it); false (status_ set)
  // when the scan does not align.
  bool StartInReference(ImuKinematics* predicted);
  ScanStatus UpdateWindow(TimeNs t_ns, const ImuPoseHistory& history,
                          const std::vector<ImuSample>& samples, ScanResult* r);
  // State k's scan at its IMU pose of the scan time (SlidingWindow::ScanTimeImuPose).
  void InsertIntoWorkingMap(int k, const std::vector<Eigen::Vector3d>& p_lidar);
  void MarginalizeIfFull();
  // State k's (or the marginalized state's) points into the output map at
  // T_world_lidar, with the attributes of its scan (pending_).
  void InsertIntoOutputMap(TimeNs state_t_ns, const std::vector<Eigen::Vector3d>& p_world);
  void SetNewestFromWindow();
  Pose3 CurrentTImuLidar() const;  // the window's extrinsic (estimate or configured)
  void ReportExtrinsic(ScanResult* r);  // smoother.estimate_extrinsics: stats_.extrinsic, r->T_imu_lidar
  // lidar.estimate_time_offset: how far the scans are moved beyond
  // lidar.time_offset onto the IMU clock (0 when off).
  TimeNs ScanTimeShiftNs() const;
  TimeNs applied_shift_ns_ = 0;  // the shift of the last processed scan (the state's time)
  // stats_.time_offset, r->time_offset_s, bound warning; history: the scan's prediction.
  void ReportTimeOffset(ScanResult* r, const ImuPoseHistory& history);

  OdometryOptions options_;
  WindowOptions window_options_;
  std::unique_ptr<SlidingWindow> window_;
  WorkingMap map_;
  OutputMap output_map_;
  ScanPreprocessor preprocessor_;
  StaticInitializer initializer_;
  Pose3 T_imu_lidar_;  // configured (the prior when smoother.estimate_extrinsics)
  OdometryStats stats_;
  std::vector<std::string> warnings_;
  DivergenceMonitor monitor_;
  TimeOffsetExcitation time_offset_excitation_;
  ReferenceLocalizer localizer_;
  Status status_;
  std::deque<ImuSample> imu_buffer_;
  ScanQueue scans_;
  // The newest estimate: where the next prediction starts.
  ImuKinematics newest_;
  Eigen::Vector3d bg_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba_ = Eigen::Vector3d::Zero();
  bool window_filled_ = false;  // a state has been marginalized
  bool flushed_ = false;        // window states written to the output map
  // The downsampled returns of the scans whose states are in the window (the
  // attributes of their points for the output map) and their results'
  // indices, oldest first; a state's entry leaves when it enters the output map.
  struct PendingScan {
    TimeNs t_ns;  // the state's time
    uint32_t scan_index;
    Scan returns;
  };
  std::deque<PendingScan> pending_;
  // Per-scan workspaces, reused.
  Scan downsampled_;
  std::vector<Eigen::Vector3d> p_lidar_end_;
  std::vector<Eigen::Vector3d> p_world_;
};

}  // namespace rvlio

#pragma once
// The IESKF backend of the odometry pipeline (see odometry.h).
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "rvlio/ieskf/ieskf.h"
#include "rvlio/lidar/preprocess.h"
#include "rvlio/map/output_map.h"
#include "rvlio/odometry/odometry.h"
#include "rvlio/odometry/scan_frontend.h"

namespace rvlio {

class IeskfOdometry : public Odometry {
 public:
  IeskfOdometry(const OdometryOptions& options, Localization localization = {});

  void AddImu(const ImuSample& imu) override;
  void AddScan(Scan scan) override;
  void Poll(std::vector<ScanResult>* out) override;
  void Finish(std::vector<ScanResult>* out) override;

  const OdometryStats& stats() const override { return stats_; }
  std::vector<std::string> warnings() const override;
  const DivergenceReport& divergence() const override { return monitor_.report(); }
  std::vector<Eigen::Vector3d> MapPoints() const override { return output_map_.Points(); }
  const Status& status() const override { return status_; }

  const FilterState& state() const { return filter_.state(); }

 private:
  void TryInitialize(const ImuSample& imu);
  void ProcessFrontScan(std::vector<ScanResult>* out);
  // Returns the mean specific force of the samples used (IMU frame).
  Eigen::Vector3d Predict(TimeNs t_end_ns);
  ScanStatus Correct(ScanResult* r);
  // Reference map: moves the state into the reference frame at the first scan.
  bool StartInReference();
  // Reference map: the map this scan is matched with, at the prediction.
  const VoxelMap& ChooseMap(AssociationCache* cache, ScanResult* r);
  // provisional: in the working map only (ProvisionalInMap), not in the output map.
  void InsertIntoMap(TimeNs t_ns, bool provisional = false);
  // lidar.estimate_time_offset: true while the first moving scans are
  // provisional in the map, until the offset converges (lidar.time_offset_map_hold).
  bool ProvisionalInMap(TimeNs t_ns);
  TimeNs map_hold_start_ns_ = -1;  // the first moving scan's time (-1: none yet)
  bool map_hold_over_ = false;
  std::optional<WorkingMap> map_before_motion_;  // the map at the first moving scan
  int64_t map_hold_scans_ = 0;
  void ReportExtrinsic(ScanResult* r);  // ieskf.estimate_extrinsics: stats_.extrinsic, r->T_imu_lidar
  // lidar.estimate_time_offset: how far the scans are moved beyond
  // lidar.time_offset (the reader's shift) onto the IMU clock (0 when off).
  TimeNs ScanTimeShiftNs() const;
  TimeNs applied_shift_ns_ = 0;  // the shift of the last processed scan (the state's time)
  void ReportTimeOffset(ScanResult* r);  // stats_.time_offset, r->time_offset_s, bound warning

  OdometryOptions options_;
  Ieskf filter_;
  WorkingMap map_;
  OutputMap output_map_;
  ScanPreprocessor preprocessor_;
  Pose3 T_imu_lidar_;
  OdometryStats stats_;
  std::vector<std::string> warnings_;
  DivergenceMonitor monitor_;
  StaticInitializer initializer_;
  TimeOffsetExcitation time_offset_excitation_;
  ReferenceLocalizer localizer_;
  Status status_;
  std::deque<ImuSample> imu_buffer_;
  ScanQueue scans_;
  // Per-scan workspaces, reused to avoid allocation in the hot path.
  Scan downsampled_;
  std::vector<Eigen::Vector3d> p_lidar_end_;
  ConstraintList choice_;  // the association that chose the map (reference runs)
};

}  // namespace rvlio

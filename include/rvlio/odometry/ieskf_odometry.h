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

// The IESKF's processing of the input, one scan at a time. Copyable: a copy
// is the whole evolving state (filter, maps, queued input, statistics), the
// snapshot lidar.time_offset_replay returns to.
class IeskfPipeline {
 public:
  IeskfPipeline(const OdometryOptions& options, Localization localization);

  void AddImu(const ImuSample& imu);
  void AddScan(Scan scan);
  // Processes the oldest queued scan when the IMU covers it (finishing: the
  // end of input, every queued scan); false when there was none.
  bool ProcessNext(bool finishing, std::vector<ScanResult>* out);
  // The end of input: drops the scans the IMU does not reach (call once).
  void StartFinishing();
  // True when ProcessNext would process a scan whose update estimates the
  // offset (the motion shows it, Ieskf::TimeOffsetObservableAt).
  bool NextScanShowsTimeOffset(bool finishing) const;
  // Replay: the offset's estimate and 1-sigma, the queued scans moved by it
  // (those that now start before the state are dropped, as AddScan would).
  void SetTimeOffset(double td_s, double std_s);
  void SetReplayedScans(int64_t n) { stats_.time_offset.replayed_scans = replayed_scans_ = n; }
  size_t queued_scans() const { return scans_.size(); }

  const OdometryStats& stats() const { return stats_; }
  std::vector<std::string> warnings() const;
  const DivergenceReport& divergence() const { return monitor_.report(); }
  std::vector<Eigen::Vector3d> MapPoints() const { return output_map_.Points(); }
  MapCloud MapWithAttributes() const { return output_map_.Cloud(); }
  const Status& status() const { return status_; }
  const Ieskf& filter() const { return filter_; }

 private:
  void TryInitialize(const ImuSample& imu);
  void ProcessFrontScan(std::vector<ScanResult>* out);
  // Returns the mean of the samples used (specific force and rate, IMU
  // frame; zero without samples).
  ImuSample Predict(TimeNs t_end_ns);
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
  int64_t replayed_scans_ = 0;
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

// The IESKF backend. With lidar.estimate_time_offset and
// lidar.time_offset_replay (docs/time_offset.md "Replay"): before the first
// scan that shows the offset, a snapshot of the pipeline is taken and the
// input from then on is also given to it; the results meanwhile are held.
// Once the offset's 1-sigma is below lidar.time_offset_replay_std, the
// pipeline continues from the snapshot with the converged offset
// (re-processing the kept input) and the held results are dropped, their CPU
// time added to the replayed results' `ms`; after time_offset_replay
// seconds without convergence (or at a stop) the held results are emitted
// and the next scan that shows the offset starts a new hold (at most three
// holds). One replay per run.
// Each scan's result is emitted once, in order.
class IeskfOdometry : public Odometry {
 public:
  IeskfOdometry(const OdometryOptions& options, Localization localization = {});

  void AddImu(const ImuSample& imu) override;
  void AddScan(Scan scan) override;
  void Poll(std::vector<ScanResult>* out) override;
  void Finish(std::vector<ScanResult>* out) override;

  const OdometryStats& stats() const override { return live_.stats(); }
  std::vector<std::string> warnings() const override { return live_.warnings(); }
  const DivergenceReport& divergence() const override { return live_.divergence(); }
  std::vector<Eigen::Vector3d> MapPoints() const override { return live_.MapPoints(); }
  MapCloud MapWithAttributes() const override { return live_.MapWithAttributes(); }
  const Status& status() const override { return live_.status(); }

  const FilterState& state() const { return live_.filter().state(); }

 private:
  enum class ReplayPhase { kWaitingForMotion, kHolding, kOver };
  bool Step(bool finishing, std::vector<ScanResult>* out);
  void EndHoldIfDue(std::vector<ScanResult>* out);
  void Replay();
  void GiveUpReplay(std::vector<ScanResult>* out);
  void CarryHeldCost(size_t replayed_scans);
  void AddHeldCost(size_t first_new, std::vector<ScanResult>* out);

  OdometryOptions options_;
  IeskfPipeline live_;
  ReplayPhase phase_ = ReplayPhase::kOver;
  std::optional<IeskfPipeline> snapshot_;  // kHolding: before the first moving scan, with the input since
  TimeNs hold_start_ns_ = 0;               // kHolding: the state's time at the snapshot
  std::vector<ScanResult> held_;           // kHolding: the live results since the snapshot
  // After a replay: the CPU ms of the dropped first processing of each scan
  // still to be replayed, oldest first (added to its replayed result's ms).
  std::deque<double> held_cost_ms_;
  static constexpr int kMaxReplayHolds = 3;  // holds per run (GiveUpReplay)
  int holds_given_up_ = 0;
};

}  // namespace rvlio

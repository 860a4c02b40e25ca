#pragma once
// The backbone of the online odometry (docs/design.md "The backbone and the
// backends"): what both online backends share, around a Backend that
// supplies the estimator's two steps, predict and update.
//
// The backbone owns the IMU buffer and the static initialization, the scan
// queue and the shift of a scan onto the IMU clock by the estimated time
// offset, the start in a reference map, the working map (what scans are
// associated with) and the output map, the per-scan report and the
// divergence monitor. One scan's path (ScanPipeline::ProcessFrontScan)
// reads as the method, in the order of the paper (Sec. 3):
//   shift -> predict -> downsample -> deskew -> associate + update -> insert -> report.
//
// A Backend (IeskfBackend, odometry/ieskf_backend.h; SmootherBackend,
// odometry/smoother_backend.h) is a class with:
//   explicit Backend(const OdometryOptions&);
//   void Initialize(const StaticAlignment&, const ImuSample& imu, std::deque<ImuSample>* imu);
//       the state at the end of the static start (the sample that ended it: imu)
//   Prediction Predict(std::deque<ImuSample>* imu, TimeNs t_end_ns);
//       the state carried to the scan's end over the buffered samples
//   void ChangeWorldFrame(const Pose3& T_ref_world, Prediction*);
//       the state (and the prediction) moved into a reference map's frame
//   ScanStatus Update(ScanContext&, ScanResult*);
//       associate the scan with the maps and correct the state (the backend's
//       own loop: the IESKF's iterations, the window's rounds)
//   void Insert(ScanContext&);
//       the scans that are final now into the working and the output map
//   void Finish(ScanContext&);
//       end of input: what the backend still holds into the output map
//   the state after the scan: time_ns(), T_world_imu(), v_world_imu(),
//       T_imu_lidar(), time_offset_s(), time_offset_std_s(), time_offset_at_bound();
//       void ReportPropagationState(ScanResult*) const: biases, gravity and
//       the pose covariance if any (the IMU-rate output of `rvlio live`)
//   online extrinsic: estimates_extrinsics(), CountExcitationScan(), extrinsic_excitation()
//   void AddReports(OdometryStats*) const; std::vector<std::string> Warnings(const OdometryStats&) const;
// A new backend is one such class and one line in Odometry::Create and at
// the end of pipeline.cpp. No I/O.
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/imu/integrator.h"
#include "rvlio/imu/pose_history.h"
#include "rvlio/lidar/preprocess.h"
#include "rvlio/map/output_map.h"
#include "rvlio/math/pose.h"
#include "rvlio/math/time_offset_excitation.h"
#include "rvlio/odometry/divergence.h"
#include "rvlio/odometry/odometry.h"
#include "rvlio/odometry/options.h"
#include "rvlio/odometry/scan_frontend.h"

namespace rvlio {

// A backend's prediction of the state at a scan's end.
struct Prediction {
  ImuKinematics at_end;  // time (the scan's end), pose and velocity predicted there
  // The IMU poses over the scan, for deskew (held by the backend until its
  // next Predict).
  const std::vector<ImuPoseSample>* poses = nullptr;
  ImuSample mean_imu;  // mean specific force and rate of the scan's IMU samples (zero: none)
};

// The output map (map.pcd, map.las) and the returns of the scans not in it
// yet. A backend inserts a scan's points once their pose is final (the IESKF
// right after the update, the smoother when the state leaves the window);
// the points keep the attributes of the scan's downsampled returns
// (map/output_map.h) and its result's index.
class OutputMapFeed {
 public:
  explicit OutputMapFeed(double resolution_m) : map_(resolution_m) {}
  // The scan being processed, before its update: the state's time at its
  // end, its result's index and its downsampled returns (referred to, not
  // copied: they must stay until Release).
  void Hold(TimeNs t_ns, uint32_t scan_index, const Scan& returns);
  // The points (world, m) of the held scan of time t_ns, returns[i] at
  // p_world[i]. Held scans older than t_ns never enter (an IESKF scan kept
  // provisional, a window state dropped unmarginalized).
  void Insert(TimeNs t_ns, const std::vector<Eigen::Vector3d>& p_world);
  // The end of the scan's step: returns not inserted yet (the smoother's
  // window) are copied to wait for their Insert; the IESKF's, inserted at
  // once, are never copied.
  void Release();
  const OutputMap& map() const { return map_; }

 private:
  struct HeldScan {
    TimeNs t_ns;
    uint32_t scan_index;
    Scan returns;
  };
  OutputMap map_;
  std::deque<HeldScan> held_;  // oldest first, copied at Release
  // The scan of the step under way (between Hold and Release), not copied.
  TimeNs current_t_ns_ = -1;
  uint32_t current_index_ = 0;
  const Scan* current_ = nullptr;
};

// What a backend's Update, Insert and Finish work with: one scan and the
// maps of the backbone.
struct ScanContext {
  TimeNs t_ns = 0;                                 // the scan's end on the IMU clock
  const std::vector<Eigen::Vector3d>* p_lidar;     // its points deskewed to t_ns, LiDAR frame
  const Prediction* prediction;
  WorkingMap* map;                                 // what scans are associated with
  OutputMapFeed* output;                           // map.pcd
  const ReferenceLocalizer* localizer;             // the reference map, when there is one
  OdometryStats* stats;
};

template <class Backend>
class ScanPipeline {
 public:
  ScanPipeline(const OdometryOptions& options, Localization localization);

  void AddImu(const ImuSample& imu);
  void AddScan(Scan scan);
  // Processes the oldest queued scan when the IMU covers its end
  // (finishing: whatever the IMU covers); false when there was none.
  bool ProcessNext(bool finishing, std::vector<ScanResult>* out);
  // The end of input: drops the scans the IMU does not reach (call once,
  // before the last ProcessNext(true) calls).
  void StartFinishing();
  // The end of input, after the last scan: what the backend still holds
  // enters the output map.
  void Finish();

  // lidar.estimate_time_offset: how far the scans are moved beyond
  // lidar.time_offset (the reader's shift) onto the IMU clock (0 when off).
  TimeNs ScanTimeShiftNs() const;
  // After the time offset's estimate was set from outside (the IESKF's
  // replay): drops the queued scans that now start before the state, as
  // AddScan would have.
  void DropScansBeforeState();
  void SetReplayedScans(int64_t n) { replayed_scans_ = stats_.time_offset.replayed_scans = n; }

  const OdometryStats& stats() const { return stats_; }
  std::vector<std::string> warnings() const;
  const DivergenceReport& divergence() const { return monitor_.report(); }
  std::vector<Eigen::Vector3d> MapPoints() const { return output_.map().Points(); }
  MapCloud MapWithAttributes() const { return output_.map().Cloud(); }
  const Status& status() const { return status_; }
  const Backend& backend() const { return backend_; }
  Backend& backend() { return backend_; }
  const ScanQueue& scans() const { return scans_; }
  const std::deque<ImuSample>& imu_buffer() const { return imu_buffer_; }
  const WorkingMap& map() const { return map_; }

 private:
  void TryInitialize(const ImuSample& imu);
  void ProcessFrontScan(std::vector<ScanResult>* out);
  // A new result for the scan: its sizes and the prediction's IMU means.
  ScanResult NewResult(const Scan& scan, const Prediction& prediction) const;
  // Reference map: the first scan aligned to it; the backend's state moves
  // into its frame. False (status_ set) when it does not align.
  bool StartInReference(Prediction* prediction);
  ScanContext Context(TimeNs t_ns, const Prediction& prediction);
  // The state after the scan, the estimated extrinsic and time offset, the
  // CPU time and the monitor's verdict.
  void Report(TimeNs t_ns, const Prediction& prediction, double start_ms, ScanResult* r);
  void ReportExtrinsic(ScanResult* r);
  void ReportTimeOffset(const Prediction& prediction, ScanResult* r);

  OdometryOptions options_;
  Backend backend_;
  WorkingMap map_;
  OutputMapFeed output_;
  ScanPreprocessor preprocessor_;
  Pose3 T_imu_lidar_prior_;  // configured (the prior of an estimated extrinsic)
  OdometryStats stats_;
  std::vector<std::string> warnings_;
  DivergenceMonitor monitor_;
  StaticInitializer initializer_;
  TimeOffsetExcitation time_offset_excitation_;
  ReferenceLocalizer localizer_;
  Status status_;
  std::deque<ImuSample> imu_buffer_;
  ScanQueue scans_;
  TimeNs applied_shift_ns_ = 0;  // the shift of the last processed scan (the state's time)
  int64_t replayed_scans_ = 0;
  bool finished_ = false;
  // Per-scan workspaces, reused to avoid allocation in the hot path.
  Scan downsampled_;
  std::vector<Eigen::Vector3d> p_lidar_end_;
};

// An Odometry that is its pipeline (the smoother; the IESKF adds its replay:
// IeskfOdometry, odometry/ieskf_odometry.h, over the pipeline_ held here).
template <class Backend>
class PipelineOdometry : public Odometry {
 public:
  PipelineOdometry(const OdometryOptions& options, Localization localization)
      : pipeline_(options, std::move(localization)) {}

  void AddImu(const ImuSample& imu) override { pipeline_.AddImu(imu); }
  void AddScan(Scan scan) override { pipeline_.AddScan(std::move(scan)); }
  void Poll(std::vector<ScanResult>* out) override {
    while (pipeline_.ProcessNext(false, out)) {
    }
  }
  void Finish(std::vector<ScanResult>* out) override {
    pipeline_.StartFinishing();
    while (pipeline_.ProcessNext(true, out)) {
    }
    pipeline_.Finish();
  }

  const OdometryStats& stats() const override { return pipeline_.stats(); }
  std::vector<std::string> warnings() const override { return pipeline_.warnings(); }
  const DivergenceReport& divergence() const override { return pipeline_.divergence(); }
  std::vector<Eigen::Vector3d> MapPoints() const override { return pipeline_.MapPoints(); }
  MapCloud MapWithAttributes() const override { return pipeline_.MapWithAttributes(); }
  const Status& status() const override { return pipeline_.status(); }

 protected:
  ScanPipeline<Backend> pipeline_;  // the live one
};

}  // namespace rvlio

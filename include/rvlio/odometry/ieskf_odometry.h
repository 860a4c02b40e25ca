#pragma once
// The IESKF's odometry: the backbone over the IESKF backend
// (ScanPipeline<IeskfBackend>, odometry/pipeline.h, odometry/ieskf_backend.h)
// and the time offset's replay around it.
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "rvlio/odometry/ieskf_backend.h"
#include "rvlio/odometry/odometry.h"
#include "rvlio/odometry/pipeline.h"

namespace rvlio {

// With lidar.estimate_time_offset and lidar.time_offset_replay
// (docs/time_offset.md "Replay"): before the first scan that shows the offset, a snapshot of the pipeline is taken and the
// input from then on is also given to it; the results meanwhile are held.
// Once the offset's 1-sigma is below lidar.time_offset_replay_std, the
// pipeline continues from the snapshot with the converged offset
// (re-processing the kept input) and the held results are dropped, their CPU
// time added to the replayed results' `ms`; after time_offset_replay
// seconds without convergence (or at a stop) the held results are emitted
// and the next scan that shows the offset starts a new hold (at most three
// holds). One replay per run.
// Each scan's result is emitted once, in order.
class IeskfOdometry : public PipelineOdometry<IeskfBackend> {
 public:
  IeskfOdometry(const OdometryOptions& options, Localization localization = {});

  void AddImu(const ImuSample& imu) override;
  void AddScan(Scan scan) override;
  void Poll(std::vector<ScanResult>* out) override;
  void Finish(std::vector<ScanResult>* out) override;

 private:
  using Pipeline = ScanPipeline<IeskfBackend>;
  enum class ReplayPhase { kWaitingForMotion, kHolding, kOver };
  // True when the live pipeline's (pipeline_) next ProcessNext would process a scan
  // whose update estimates the offset (the motion shows it,
  // Ieskf::TimeOffsetObservableAt).
  bool NextScanShowsTimeOffset(bool finishing) const;
  bool Step(bool finishing, std::vector<ScanResult>* out);
  void EndHoldIfDue(std::vector<ScanResult>* out);
  void Replay();
  void GiveUpReplay(std::vector<ScanResult>* out);
  void CarryHeldCost(size_t replayed_scans);
  void AddHeldCost(size_t first_new, std::vector<ScanResult>* out);

  OdometryOptions options_;
  ReplayPhase phase_ = ReplayPhase::kOver;
  std::optional<Pipeline> snapshot_;  // kHolding: before the first moving scan, with the input since
  TimeNs hold_start_ns_ = 0;          // kHolding: the state's time at the snapshot
  std::vector<ScanResult> held_;      // kHolding: the live results since the snapshot
  // After a replay: the CPU ms of the dropped first processing of each scan
  // still to be replayed, oldest first (added to its replayed result's ms).
  std::deque<double> held_cost_ms_;
  static constexpr int kMaxReplayHolds = 3;  // holds per run (GiveUpReplay)
  int holds_given_up_ = 0;
};

}  // namespace rvlio

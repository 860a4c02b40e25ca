// The IESKF's odometry: the backbone over the IESKF backend, and the time
// offset's replay.
#include "rvlio/odometry/ieskf_odometry.h"

#include <algorithm>
#include <utility>

namespace rvlio {

IeskfOdometry::IeskfOdometry(const OdometryOptions& options, Localization localization)
    : PipelineOdometry<IeskfBackend>(options, std::move(localization)), options_(options) {
  if (options.lidar.estimate_time_offset && options.lidar.time_offset_replay > 0.0)
    phase_ = ReplayPhase::kWaitingForMotion;
}

void IeskfOdometry::AddImu(const ImuSample& imu) {
  pipeline_.AddImu(imu);
  if (snapshot_) snapshot_->AddImu(imu);
}

void IeskfOdometry::AddScan(Scan scan) {
  if (snapshot_) snapshot_->AddScan(scan);
  pipeline_.AddScan(std::move(scan));
}

void IeskfOdometry::Poll(std::vector<ScanResult>* out) {
  while (Step(false, out)) {
  }
}

// At the end of input a hold ends with the results there are: the held ones
// when the offset has not converged by then.
void IeskfOdometry::Finish(std::vector<ScanResult>* out) {
  pipeline_.StartFinishing();
  if (snapshot_) snapshot_->StartFinishing();
  while (Step(true, out)) {
  }
  if (phase_ == ReplayPhase::kHolding) GiveUpReplay(out);
  pipeline_.Finish();
}

bool IeskfOdometry::NextScanShowsTimeOffset(bool finishing) const {
  const ScanQueue& scans = pipeline_.scans();
  if (!pipeline_.status().ok() || scans.empty() || pipeline_.map().Empty()) return false;
  const TimeNs shift_ns = pipeline_.ScanTimeShiftNs();
  if (!finishing && !scans.FrontReady(pipeline_.imu_buffer(), shift_ns)) return false;
  return pipeline_.backend().filter().TimeOffsetObservableAt(pipeline_.imu_buffer(),
                                                             scans.front().t_end_ns + shift_ns);
}

// One scan of the live pipeline; the snapshot is taken before the first scan
// that shows the offset, the results of the hold go to held_.
bool IeskfOdometry::Step(bool finishing, std::vector<ScanResult>* out) {
  if (phase_ == ReplayPhase::kWaitingForMotion && NextScanShowsTimeOffset(finishing)) {
    snapshot_ = pipeline_;
    hold_start_ns_ = pipeline_.backend().time_ns();
    phase_ = ReplayPhase::kHolding;
  }
  const bool holding = phase_ == ReplayPhase::kHolding;
  const size_t first_new = out->size();
  if (!pipeline_.ProcessNext(finishing, holding ? &held_ : out)) return false;
  if (holding)
    EndHoldIfDue(out);
  else if (!held_cost_ms_.empty())
    AddHeldCost(first_new, out);
  return true;
}

void IeskfOdometry::EndHoldIfDue(std::vector<ScanResult>* out) {
  if (!pipeline_.status().ok()) return GiveUpReplay(out);
  const IeskfBackend& backend = pipeline_.backend();
  if (backend.time_offset_std_s() < options_.lidar.time_offset_replay_std) return Replay();
  if (NsToSeconds(backend.time_ns() - hold_start_ns_) >= options_.lidar.time_offset_replay)
    GiveUpReplay(out);
}

// The snapshot continues with the converged estimate, keeping its 1-sigma
// (uncorrelated with the state at the snapshot, which the scans at rest
// did not tie to it); the following Steps re-process the kept input.
void IeskfOdometry::Replay() {
  const IeskfBackend& converged = pipeline_.backend();
  snapshot_->backend().filter().SetTimeOffset(converged.time_offset_s(),
                                              converged.time_offset_std_s());
  snapshot_->DropScansBeforeState();
  // The snapshot queues the scans the hold processed (less those the new
  // shift dropped) and those the live pipeline still queues: the difference
  // is the scans processed again.
  const size_t queued_in_both = pipeline_.scans().size();
  const size_t queued_in_snapshot = snapshot_->scans().size();
  const size_t replayed = queued_in_snapshot > queued_in_both ? queued_in_snapshot - queued_in_both : 0;
  snapshot_->SetReplayedScans(static_cast<int64_t>(replayed));
  CarryHeldCost(replayed);
  pipeline_ = std::move(*snapshot_);
  snapshot_.reset();
  held_.clear();
  phase_ = ReplayPhase::kOver;
}

// A replayed scan's `ms` is both its processings: the held result's CPU time
// (dropped with it) plus the replay's. The scans the new shift dropped are
// the oldest; their cost goes to the first replayed result, so the run's
// total CPU time (summary.json per_scan_ms, total) keeps the whole replay.
void IeskfOdometry::CarryHeldCost(size_t replayed_scans) {
  held_cost_ms_.clear();
  for (const ScanResult& r : held_) held_cost_ms_.push_back(r.ms);
  while (held_cost_ms_.size() > std::max<size_t>(replayed_scans, 1)) {
    const double dropped_ms = held_cost_ms_.front();
    held_cost_ms_.pop_front();
    held_cost_ms_.front() += dropped_ms;
  }
}

void IeskfOdometry::AddHeldCost(size_t first_new, std::vector<ScanResult>* out) {
  for (size_t i = first_new; i < out->size() && !held_cost_ms_.empty(); ++i) {
    (*out)[i].ms += held_cost_ms_.front();
    held_cost_ms_.pop_front();
  }
}

// The held results are emitted as they are, and the next scan that shows the
// offset starts a new hold: a scan at rest whose noise passed the motion test
// (tunnel seed 5: at 1.3 s of a 3 s static start) must not use up the replay
// of the real start of the motion. Each hold keeps at most one window, and
// at most kMaxReplayHolds are made: on a recording whose estimate never
// converges, the pipeline (its maps) is not copied every window to the end.
void IeskfOdometry::GiveUpReplay(std::vector<ScanResult>* out) {
  for (ScanResult& r : held_) out->push_back(std::move(r));
  held_.clear();
  snapshot_.reset();
  ++holds_given_up_;
  phase_ = holds_given_up_ < kMaxReplayHolds ? ReplayPhase::kWaitingForMotion : ReplayPhase::kOver;
}

}  // namespace rvlio

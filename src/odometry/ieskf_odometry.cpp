// The IESKF backend of the odometry pipeline (paper-exact mode).
#include "rvlio/lidar/extrinsics.h"
#include "rvlio/odometry/ieskf_odometry.h"

#include <algorithm>
#include <limits>
#include <utility>

#include "rvlio/common/cpu_time.h"
#include "rvlio/common/parallel.h"
#include "rvlio/constraints/plane_association.h"
#include "rvlio/lidar/deskew.h"

namespace rvlio {

namespace {

// The divergence monitor's options. With lidar.estimate_time_offset the
// rotation check (scans against the gyro) is off: until the offset's estimate
// has converged, that disagreement is what the estimate absorbs, not a wrong
// extrinsic rotation.
DivergenceOptions MonitorOptions(const OdometryOptions& options) {
  DivergenceOptions divergence = options.divergence;
  if (options.lidar.estimate_time_offset)
    divergence.max_lidar_rotation_deg = std::numeric_limits<double>::infinity();
  return divergence;
}

// Biases, gravity and the pose covariance for the IMU-rate output. The
// filter's rotation error is a right perturbation (R = R_hat Exp(d)); about
// the world axes it is R_hat d, so the covariance's rotation rows turn by R_hat.
void SetPropagationState(const Ieskf& filter, ScanResult* r) {
  const FilterState& x = filter.state();
  r->bg_imu = x.bg;
  r->ba_imu = x.ba;
  r->g_world = x.g_world;
  Eigen::Matrix<double, 6, 6> J = Eigen::Matrix<double, 6, 6>::Zero();
  J.block<3, 3>(0, FilterState::kPos) = Eigen::Matrix3d::Identity();
  J.block<3, 3>(3, FilterState::kRot) = x.R_world_imu;
  const Eigen::Matrix<double, 6, 6> P = filter.covariance().topLeftCorner<6, 6>();
  r->pose_covariance_world = J * P * J.transpose();
}

}  // namespace

IeskfOdometry::IeskfOdometry(const OdometryOptions& options, Localization localization)
    : options_(options), live_(options, std::move(localization)) {
  if (options.lidar.estimate_time_offset && options.lidar.time_offset_replay > 0.0)
    phase_ = ReplayPhase::kWaitingForMotion;
}

void IeskfOdometry::AddImu(const ImuSample& imu) {
  live_.AddImu(imu);
  if (snapshot_) snapshot_->AddImu(imu);
}

void IeskfOdometry::AddScan(Scan scan) {
  if (snapshot_) snapshot_->AddScan(scan);
  live_.AddScan(std::move(scan));
}

void IeskfOdometry::Poll(std::vector<ScanResult>* out) {
  while (Step(false, out)) {
  }
}

// At the end of input a hold ends with the results there are: the held ones
// when the offset has not converged by then.
void IeskfOdometry::Finish(std::vector<ScanResult>* out) {
  live_.StartFinishing();
  if (snapshot_) snapshot_->StartFinishing();
  while (Step(true, out)) {
  }
  if (phase_ == ReplayPhase::kHolding) GiveUpReplay(out);
}

// One scan of the live pipeline; the snapshot is taken before the first scan
// that shows the offset, the results of the hold go to held_.
bool IeskfOdometry::Step(bool finishing, std::vector<ScanResult>* out) {
  if (phase_ == ReplayPhase::kWaitingForMotion && live_.NextScanShowsTimeOffset(finishing)) {
    snapshot_ = live_;
    hold_start_ns_ = live_.filter().time_ns();
    phase_ = ReplayPhase::kHolding;
  }
  const bool holding = phase_ == ReplayPhase::kHolding;
  const size_t first_new = out->size();
  if (!live_.ProcessNext(finishing, holding ? &held_ : out)) return false;
  if (holding)
    EndHoldIfDue(out);
  else if (!held_cost_ms_.empty())
    AddHeldCost(first_new, out);
  return true;
}

void IeskfOdometry::EndHoldIfDue(std::vector<ScanResult>* out) {
  if (!live_.status().ok()) return GiveUpReplay(out);
  if (live_.filter().time_offset_std_s() < options_.lidar.time_offset_replay_std) return Replay();
  if (NsToSeconds(live_.filter().time_ns() - hold_start_ns_) >= options_.lidar.time_offset_replay)
    GiveUpReplay(out);
}

// The snapshot continues with the converged estimate, keeping its 1-sigma
// (uncorrelated with the state at the snapshot, which the scans at rest
// did not tie to it); the following Steps re-process the kept input.
void IeskfOdometry::Replay() {
  const Ieskf& converged = live_.filter();
  snapshot_->SetTimeOffset(converged.time_offset_s(), converged.time_offset_std_s());
  // The snapshot queues the scans the hold processed (less those the new
  // shift dropped) and those the live pipeline still queues: the difference
  // is the scans processed again.
  const size_t queued_in_both = live_.queued_scans();
  const size_t queued_in_snapshot = snapshot_->queued_scans();
  const size_t replayed = queued_in_snapshot > queued_in_both ? queued_in_snapshot - queued_in_both : 0;
  snapshot_->SetReplayedScans(static_cast<int64_t>(replayed));
  CarryHeldCost(replayed);
  live_ = std::move(*snapshot_);
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

IeskfPipeline::IeskfPipeline(const OdometryOptions& options, Localization localization)
    : options_(options),
      filter_(options.ieskf, options.imu, options.constraints, options.rv, options.lidar,
              options.degeneracy),
      map_(options.map, options.ieskf.estimate_extrinsics),
      output_map_(options.map.output_resolution),
      preprocessor_(options.lidar),
      T_imu_lidar_(ImuTLidar(options.extrinsics)),
      monitor_(MonitorOptions(options), options.constraints.lidar_noise, options.imu.gravity,
               options.lidar.time_offset_max),
      initializer_(options.imu.init_duration),
      localizer_(std::move(localization), options.localization, options.constraints) {}

void IeskfPipeline::AddImu(const ImuSample& imu) {
  if (!AcceptImu(imu, imu_buffer_, SecondsToNs(options_.imu.max_gap), &stats_)) return;
  scans_.NoteImu(imu.t_ns);
  if (!stats_.initialized) {
    TryInitialize(imu);
    return;
  }
  imu_buffer_.push_back(imu);
}

// Static alignment once imu.init_duration of samples has been collected.
void IeskfPipeline::TryInitialize(const ImuSample& imu) {
  const std::optional<StaticAlignment> a = initializer_.Add(imu);
  if (!a) return;
  FilterState x0;
  x0.R_world_imu = a->R_world_imu;
  x0.g_world = a->g_world;
  x0.bg = a->gyro_bias;
  x0.R_imu_lidar = T_imu_lidar_.R;
  x0.t_imu_lidar = T_imu_lidar_.t;
  filter_.Initialize(x0, imu.t_ns, imu);
  stats_.initialized = true;
  stats_.started_moving = a->moving;
  if (a->moving) warnings_.push_back(MovingStartWarning(*a));
}

std::vector<std::string> IeskfPipeline::warnings() const {
  std::vector<std::string> w = warnings_;
  for (std::string& q : StatsWarnings(stats_)) w.push_back(std::move(q));
  return w;
}

void IeskfPipeline::AddScan(Scan scan) {
  // The filter's time is on the IMU clock, the queued scans' on the reader's
  // (before the estimated shift): the state is at the last processed scan's end
  // moved by that scan's shift.
  scans_.Add(std::move(scan), stats_.initialized, filter_.time_ns() - applied_shift_ns_,
             &stats_);
}

bool IeskfPipeline::ProcessNext(bool finishing, std::vector<ScanResult>* out) {
  if (!status_.ok() || scans_.empty()) return false;
  if (!finishing && !scans_.FrontReady(imu_buffer_, ScanTimeShiftNs())) return false;
  ProcessFrontScan(out);
  return true;
}

void IeskfPipeline::StartFinishing() {
  scans_.DropPastImu(SecondsToNs(options_.imu.max_gap), &stats_);
}

bool IeskfPipeline::NextScanShowsTimeOffset(bool finishing) const {
  if (!status_.ok() || scans_.empty() || map_.Empty()) return false;
  if (!finishing && !scans_.FrontReady(imu_buffer_, ScanTimeShiftNs())) return false;
  return filter_.TimeOffsetObservableAt(imu_buffer_, scans_.front().t_end_ns + ScanTimeShiftNs());
}

void IeskfPipeline::SetTimeOffset(double td_s, double std_s) {
  filter_.SetTimeOffset(td_s, std_s);
  scans_.DropStartingBefore(filter_.time_ns() - ScanTimeShiftNs(), &stats_);
}

// The scan is moved onto the IMU clock by the current estimate (prediction
// and deskew at the moved times); the update then refines the estimate
// (Ieskf::Update, ScanTimeMotion). The result's stamp and pose are the
// filter's: the IMU at the moved scan end. A scan the estimate's change since
// it was queued moved to end at or before the filter's time is skipped
// (ScanQueue::PopFrontShifted), so the stamps always increase.
void IeskfPipeline::ProcessFrontScan(std::vector<ScanResult>* out) {
  const double start_ms = WorkCpuMs();  // association helpers included
  const TimeNs shift_ns = ScanTimeShiftNs();
  std::optional<Scan> shifted = scans_.PopFrontShifted(shift_ns, filter_.time_ns(), &stats_);
  if (!shifted) return;
  applied_shift_ns_ = shift_ns;
  Scan& scan = *shifted;
  const ImuSample mean_imu = Predict(scan.t_end_ns);
  preprocessor_.Downsample(scan, &downsampled_);
  if (static_cast<int>(downsampled_.points.size()) < kMinScanPoints) {
    ++stats_.scans_too_few_points;
    filter_.ClearPoseHistory();
    return;
  }
  DeskewToScanEnd(filter_.pose_history(), filter_.state().T_imu_lidar(), downsampled_.points,
                  scan.t_end_ns, &p_lidar_end_);
  if (localizer_.enabled() && !localizer_.started() && !StartInReference()) return;
  ScanResult r;
  r.degeneracy.method = options_.degeneracy.method;
  r.raw_points = static_cast<int>(scan.points.size());
  r.mean_acc_imu = mean_imu.acc_imu;
  r.mean_gyro_imu = mean_imu.gyro_imu;
  r.downsampled_points = static_cast<int>(p_lidar_end_.size());
  r.status = map_.Empty() && !localizer_.enabled() ? ScanStatus::kMapInit : Correct(&r);
  InsertIntoMap(scan.t_end_ns, ProvisionalInMap(scan.t_end_ns));
  ReportExtrinsic(&r);
  ReportTimeOffset(&r);
  filter_.ClearPoseHistory();
  r.t_ns = scan.t_end_ns;
  r.T_world_imu = filter_.state().T_world_imu();
  r.v_world_imu = filter_.state().v_world_imu;
  SetPropagationState(filter_, &r);
  r.ms = WorkCpuMs() - start_ms;
  r.health.divergence_mask = monitor_.Check(HealthSampleOf(r));
  ++stats_.scans_processed;
  out->push_back(std::move(r));
}

// Propagates with every buffered IMU sample up to the scan end, then to the
// scan end itself.
ImuSample IeskfPipeline::Predict(TimeNs t_end_ns) {
  ImuSample mean;
  mean.t_ns = t_end_ns;
  int n = 0;
  while (!imu_buffer_.empty() && imu_buffer_.front().t_ns <= t_end_ns) {
    filter_.Propagate(imu_buffer_.front());
    mean.acc_imu += imu_buffer_.front().acc_imu;
    mean.gyro_imu += imu_buffer_.front().gyro_imu;
    ++n;
    imu_buffer_.pop_front();
  }
  filter_.PropagateTo(t_end_ns);
  if (n > 0) {
    mean.acc_imu /= n;
    mean.gyro_imu /= n;
  }
  return mean;
}

// Associate -> RV -> Update, iterated inside the filter (paper Alg. 3).
// The iterations of one scan share an AssociationCache: a point whose world
// position moved less than constraints.reuse_distance since its last k-NN
// search keeps that plane (with a fresh residual), so the later iterations,
// which move the pose by millimetres, mostly skip the search (the dominant
// cost, bench/RESULTS.md). A new cache per scan: the map changed since.
// With a reference map, the scan is matched with the reference, or with the
// working map when it overlaps the reference too little at the prediction
// (ReferenceLocalizer::Associate; its search fills the cache, which the
// first iteration then reuses).
ScanStatus IeskfPipeline::Correct(ScanResult* r) {
  AssociationCache cache(options_.constraints.reuse_distance);
  const VoxelMap& search = localizer_.enabled() ? ChooseMap(&cache, r) : map_.map();
  const AssociateFn associate = [this, &cache, &search](const FilterState& x,
                                                        ConstraintList* constraints) {
    AssociationStats stats;
    Associate(p_lidar_end_, x.T_world_imu(), x.T_imu_lidar(), search, options_.constraints,
              constraints, &stats, &cache, ResolveThreads(options_.constraints.threads));
  };
  const IeskfUpdateResult u = filter_.Update(associate);
  r->constraints = u.num_constraints;
  r->iterations = u.iterations;
  r->rv = u.rv;
  r->degeneracy = u.degeneracy;
  r->health.nis_per_dof = u.nis_per_dof;
  r->health.lidar_rotation_imu = u.lidar_rotation_imu;
  if (u.ok) {
    r->health.residual_median_m = u.residuals.median_abs_m;
    r->health.residual_rms_m = u.residuals.rms_m;
  }
  if (u.diverged) {
    ++stats_.diverged_resets;
    return ScanStatus::kDiverged;
  }
  if (!u.ok) {
    ++stats_.predict_only;
    return ScanStatus::kPredictOnly;
  }
  return ScanStatus::kUpdated;
}

const VoxelMap& IeskfPipeline::ChooseMap(AssociationCache* cache, ScanResult* r) {
  const FilterState& x = filter_.state();
  return localizer_.Associate(p_lidar_end_, x.T_world_imu(), x.T_imu_lidar(), map_.map(), cache,
                              ResolveThreads(options_.constraints.threads), &choice_, r);
}

// The first scan aligned to the reference from the initial pose; the whole
// state follows into the reference frame. False (status_ set) when it does
// not align.
bool IeskfPipeline::StartInReference() {
  const FilterState& x = filter_.state();
  StatusOr<Pose3> T_ref_world =
      localizer_.Start(filter_.time_ns(), p_lidar_end_, x.T_world_imu(), x.T_imu_lidar());
  if (!T_ref_world.ok()) {
    status_ = T_ref_world.status();
    return false;
  }
  filter_.ChangeWorldFrame(*T_ref_world);
  return true;
}

void IeskfPipeline::ReportExtrinsic(ScanResult* r) {
  if (!options_.ieskf.estimate_extrinsics) return;
  filter_.CountExcitationScan();
  r->T_imu_lidar = filter_.state().T_imu_lidar();
  stats_.extrinsic = MakeExtrinsicReport(filter_.extrinsic_excitation(), T_imu_lidar_,
                                         filter_.state().T_imu_lidar());
  stats_.extrinsic.map_rebuilds = map_.rebuilds();
}

TimeNs IeskfPipeline::ScanTimeShiftNs() const {
  if (!options_.lidar.estimate_time_offset) return 0;
  return SecondsToNs(filter_.time_offset_s() - options_.lidar.time_offset);
}

void IeskfPipeline::ReportTimeOffset(ScanResult* r) {
  if (!options_.lidar.estimate_time_offset) return;
  if (!filter_.pose_history().empty())
    time_offset_excitation_.CountScan(filter_.time_ns(), filter_.pose_history().back().gyro_imu,
                                      filter_.state().v_world_imu);
  r->time_offset_s = filter_.time_offset_s();
  r->time_offset_std_s = filter_.time_offset_std_s();
  UpdateTimeOffsetReport(time_offset_excitation_, options_.lidar, filter_.time_offset_s(),
                         filter_.time_offset_std_s(), filter_.time_offset_at_bound(),
                         filter_.time_ns(), &stats_.time_offset);
  stats_.time_offset.map_hold_scans = map_hold_scans_;
  stats_.time_offset.replayed_scans = replayed_scans_;
}

// The map hold (lidar.time_offset_map_hold, docs/time_offset.md "Map hold"):
// the offset is not observed at rest, so the first moving scans are predicted,
// deskewed and placed with the prior offset, and the filter cannot revisit the
// map it builds from them. At the first moving scan the working map is copied
// (the scans at rest, which the offset does not affect); the moving scans are
// then inserted provisionally (registration keeps a fresh map) and kept out of
// the output map. When the offset's 1-sigma falls below
// lidar.time_offset_map_std, the working map returns to the copy, so the
// provisional scans, deskewed and placed with the unconverged offset, leave
// it, and the scans from then on rebuild it. If the offset does not converge
// within time_offset_map_hold seconds of motion, the provisional scans stay.
// Memory: one copy of the working map, once per run.
bool IeskfPipeline::ProvisionalInMap(TimeNs t_ns) {
  if (map_hold_over_ || !options_.lidar.estimate_time_offset ||
      options_.lidar.time_offset_map_hold <= 0.0 || map_.Empty())
    return false;
  if (map_hold_start_ns_ < 0) {
    if (!filter_.time_offset_observed()) return false;  // at rest: the offset does not matter
    map_hold_start_ns_ = t_ns;
    map_before_motion_ = map_;
  }
  const bool converged = filter_.time_offset_std_s() < options_.lidar.time_offset_map_std;
  if (converged) map_ = std::move(*map_before_motion_);
  map_hold_over_ =
      converged || NsToSeconds(t_ns - map_hold_start_ns_) >= options_.lidar.time_offset_map_hold;
  if (map_hold_over_) {
    map_before_motion_.reset();
    return false;
  }
  ++map_hold_scans_;
  return true;
}

// The scan's points were deskewed to its end on the LiDAR clock, which the
// estimated offset puts at the filter's ScanTimeImuPose().
void IeskfPipeline::InsertIntoMap(TimeNs t_ns, bool provisional) {
  const FilterState& x = filter_.state();
  const Pose3 T_world_imu =
      options_.lidar.estimate_time_offset ? filter_.ScanTimeImuPose() : x.T_world_imu();
  const std::vector<Eigen::Vector3d>& p_world =
      map_.InsertScan(t_ns, T_world_imu, x.T_imu_lidar(), p_lidar_end_);
  // This scan's result is the next one out: its index is the count so far.
  if (!provisional)
    output_map_.InsertScan(p_world, downsampled_, static_cast<uint32_t>(stats_.scans_processed));
}

}  // namespace rvlio

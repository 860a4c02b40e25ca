// The sliding-window smoother backend of the odometry pipeline.
#include "rvlio/lidar/extrinsics.h"
#include "rvlio/odometry/smoother_odometry.h"

#include <utility>

#include "rvlio/common/check.h"
#include "rvlio/common/cpu_time.h"
#include "rvlio/common/parallel.h"
#include "rvlio/constraints/plane_association.h"
#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/imu/pose_history.h"
#include "rvlio/imu/preintegration.h"
#include "rvlio/lidar/deskew.h"

namespace rvlio {
namespace {

// The window's sections of the configuration, through the options reflection.
WindowOptions MakeWindowOptions(const OdometryOptions& o) {
  WindowOptions w;
  CopySections(o, &w);
  w.rv = EffectiveRvOptions(o.rv, o.degeneracy);
  return w;
}

// The IMU motion held at the end of a predicted interval (the last knot's).
ScanTimeMotion MotionAtEnd(const ImuPoseHistory& history) {
  ScanTimeMotion m;
  if (history.empty()) return m;
  m.gyro_imu = history.samples().back().gyro_imu;
  m.acc_world = history.samples().back().acc_world;
  return m;
}

// The mean specific force and rate of the samples in (t0_ns, t1_ns] (zero
// without samples).
ImuSample MeanImu(const std::vector<ImuSample>& samples, TimeNs t0_ns, TimeNs t1_ns) {
  ImuSample mean;
  mean.t_ns = t1_ns;
  int n = 0;
  for (const ImuSample& s : samples) {
    if (s.t_ns <= t0_ns || s.t_ns > t1_ns) continue;
    mean.acc_imu += s.acc_imu;
    mean.gyro_imu += s.gyro_imu;
    ++n;
  }
  if (n > 0) {
    mean.acc_imu /= n;
    mean.gyro_imu /= n;
  }
  return mean;
}

}  // namespace

SmootherOdometry::SmootherOdometry(const OdometryOptions& options, Localization localization)
    : options_(options),
      window_options_(MakeWindowOptions(options)),
      map_(options.map, options.smoother.estimate_extrinsics),
      output_map_(options.map.output_resolution),
      preprocessor_(options.lidar),
      initializer_(options.imu.init_duration),
      T_imu_lidar_(ImuTLidar(options.extrinsics)),
      monitor_(options.divergence, options.constraints.lidar_noise, options.imu.gravity,
               options.lidar.time_offset_max),
      localizer_(std::move(localization), options.localization, options.constraints) {}

void SmootherOdometry::AddImu(const ImuSample& imu) {
  if (!AcceptImu(imu, imu_buffer_, SecondsToNs(options_.imu.max_gap), &stats_)) return;
  scans_.NoteImu(imu.t_ns);
  if (!stats_.initialized) {
    TryInitialize(imu);
    return;
  }
  imu_buffer_.push_back(imu);
}

// Static alignment as in the IESKF backend: gravity, gyro bias, zero
// velocity, identity yaw at the origin.
void SmootherOdometry::TryInitialize(const ImuSample& imu) {
  const std::optional<StaticAlignment> a = initializer_.Add(imu);
  if (!a) return;
  newest_.t_ns = imu.t_ns;
  newest_.R_world_imu = a->R_world_imu;
  bg_ = a->gyro_bias;
  window_options_.g_world = a->g_world;
  window_ = std::make_unique<SlidingWindow>(window_options_);
  imu_buffer_.push_back(imu);  // the signal at the start of the first interval
  stats_.initialized = true;
  stats_.started_moving = a->moving;
  if (a->moving) warnings_.push_back(MovingStartWarning(*a));
}

void SmootherOdometry::AddScan(Scan scan) {
  // newest_ is on the IMU clock, the queued scans on the reader's (before the
  // estimated shift): newest_ is at the last processed scan's end moved by its shift.
  scans_.Add(std::move(scan), stats_.initialized, newest_.t_ns - applied_shift_ns_, &stats_);
}

void SmootherOdometry::Poll(std::vector<ScanResult>* out) {
  while (status_.ok() && scans_.FrontReady(imu_buffer_, ScanTimeShiftNs())) ProcessFrontScan(out);
}

// The remaining scans, then the states still in the window enter the
// output map at their final estimates.
void SmootherOdometry::Finish(std::vector<ScanResult>* out) {
  scans_.DropPastImu(SecondsToNs(options_.imu.max_gap), &stats_);
  while (status_.ok() && !scans_.empty()) ProcessFrontScan(out);
  if (flushed_ || !window_ || !status_.ok()) return;
  flushed_ = true;
  for (int k = 0; k < window_->size(); ++k) {
    TransformPoints(window_->ScanTimeImuPose(k) * CurrentTImuLidar(), window_->points(k),
                    &p_world_);
    InsertIntoOutputMap(window_->state(k).t_ns, p_world_);
  }
}

// Predict -> Downsample -> Deskew -> Add + Optimize -> Insert -> Marginalize.
// With lidar.estimate_time_offset the scan is first moved onto the IMU clock
// by the current estimate (the window then refines it); one the estimate's
// change moved to end at or before the newest state is skipped.
void SmootherOdometry::ProcessFrontScan(std::vector<ScanResult>* out) {
  const double start_ms = WorkCpuMs();  // association helpers included
  const TimeNs shift_ns = ScanTimeShiftNs();
  std::optional<Scan> shifted = scans_.PopFrontShifted(shift_ns, newest_.t_ns, &stats_);
  if (!shifted) return;
  applied_shift_ns_ = shift_ns;
  Scan& scan = *shifted;
  const Eigen::Vector3d& g = window_options_.g_world;
  const std::vector<ImuSample> samples = ImuCovering(newest_.t_ns, scan.t_end_ns);
  const ImuPoseHistory history =
      ImuPoseHistory::Integrate(newest_, samples, scan.t_end_ns, bg_, ba_, g);
  preprocessor_.Downsample(scan, &downsampled_);
  if (static_cast<int>(downsampled_.points.size()) < kMinScanPoints) {
    ++stats_.scans_too_few_points;  // the next state's IMU factor spans this scan
    return;
  }
  DeskewToScanEnd(history.samples(), CurrentTImuLidar(),
                  downsampled_.points, scan.t_end_ns, &p_lidar_end_);
  ScanResult r;
  r.degeneracy.method = options_.degeneracy.method;
  r.raw_points = static_cast<int>(scan.points.size());
  r.downsampled_points = static_cast<int>(p_lidar_end_.size());
  const ImuSample mean_imu = MeanImu(samples, newest_.t_ns, scan.t_end_ns);
  r.mean_acc_imu = mean_imu.acc_imu;
  r.mean_gyro_imu = mean_imu.gyro_imu;
  ImuKinematics predicted = history.Newest();
  if (localizer_.enabled() && !localizer_.started() && !StartInReference(&predicted)) return;
  r.status = window_->empty() ? StartWindow(scan.t_end_ns, predicted)
                              : UpdateWindow(scan.t_end_ns, history, samples, &r);
  if (localizer_.enabled() && r.status == ScanStatus::kMapInit) {  // aligned to the reference
    r.map_overlap = localizer_.start_overlap();
    r.localized = true;
  }
  pending_.push_back({scan.t_end_ns, static_cast<uint32_t>(stats_.scans_processed), downsampled_});
  SetNewestFromWindow();
  MarginalizeIfFull();
  ReportExtrinsic(&r);
  ReportTimeOffset(&r, history);
  DropImuBefore(scan.t_end_ns);
  r.t_ns = scan.t_end_ns;
  r.T_world_imu = Pose3(newest_.R_world_imu, newest_.p_world_imu);
  r.v_world_imu = newest_.v_world_imu;
  r.bg_imu = bg_;
  r.ba_imu = ba_;
  r.g_world = window_options_.g_world;
  r.ms = WorkCpuMs() - start_ms;
  r.health.divergence_mask = monitor_.Check(HealthSampleOf(r));
  ++stats_.scans_processed;
  out->push_back(std::move(r));
}

std::vector<ImuSample> SmootherOdometry::ImuCovering(TimeNs t0_ns, TimeNs t1_ns) const {
  std::vector<ImuSample> samples;
  for (const ImuSample& s : imu_buffer_) {
    if (!samples.empty() && s.t_ns <= t0_ns) samples.clear();  // keep the last one <= t0
    samples.push_back(s);
    if (s.t_ns >= t1_ns) break;
  }
  return samples;
}

// Consecutive samples around or inside [t0, t1] farther apart than
// imu.max_gap (or [t0, t1] not covered): the preintegration would bridge a
// stretch without measurements. `samples`: from ImuCovering(t0, t1).
bool SmootherOdometry::HasImuGap(const std::vector<ImuSample>& samples, TimeNs t0_ns,
                                 TimeNs t1_ns) const {
  const TimeNs max_gap_ns = SecondsToNs(options_.imu.max_gap);
  if (samples.empty()) return true;
  if (samples.front().t_ns - t0_ns > max_gap_ns || t1_ns - samples.back().t_ns > max_gap_ns)
    return true;
  for (size_t i = 1; i < samples.size(); ++i)
    if (samples[i].t_ns - samples[i - 1].t_ns > max_gap_ns) return true;
  return false;
}

void SmootherOdometry::DropImuBefore(TimeNs t_ns) {
  while (imu_buffer_.size() >= 2 && imu_buffer_[1].t_ns <= t_ns) imu_buffer_.pop_front();
}

// The first scan: the first window state (with the prior of the static
// initialization) at the predicted pose; its points start the map.
ScanStatus SmootherOdometry::StartWindow(TimeNs t_ns, const ImuKinematics& predicted) {
  window_->Start(t_ns, PoseBlock(Eigen::Quaterniond(predicted.R_world_imu), predicted.p_world_imu),
                 SpeedBiasBlock{predicted.v_world_imu, bg_, ba_}, p_lidar_end_);
  InsertIntoWorkingMap(0, p_lidar_end_);
  return ScanStatus::kMapInit;
}

// Adds the scan's state (IMU factor from the newest state unless the interval
// is empty or has a gap) and optimizes the window.
ScanStatus SmootherOdometry::UpdateWindow(TimeNs t_ns, const ImuPoseHistory& history,
                                          const std::vector<ImuSample>& samples, ScanResult* r) {
  const ImuKinematics predicted = history.Newest();
  std::optional<ImuPreintegration> imu;
  if (t_ns > newest_.t_ns && !HasImuGap(samples, newest_.t_ns, t_ns))
    imu = ImuPreintegration::FromSamples(samples, newest_.t_ns, t_ns,
                                         ImuNoise::FromOptions(options_.imu), bg_, ba_);
  window_->Add(t_ns, PoseBlock(Eigen::Quaterniond(predicted.R_world_imu), predicted.p_world_imu),
               SpeedBiasBlock{predicted.v_world_imu, bg_, ba_}, std::move(imu), p_lidar_end_,
               MotionAtEnd(history));
  const std::vector<Eigen::Vector3d>* newest_points = &window_->points(window_->size() - 1);
  const ScanAssociateFn associate = [this, newest_points, r](
                                        const std::vector<Eigen::Vector3d>& p_lidar,
                                        const Pose3& T_world_imu, ConstraintList* out) {
    const int threads = ResolveThreads(options_.constraints.threads);
    if (!localizer_.enabled()) {
      Associate(p_lidar, T_world_imu, CurrentTImuLidar(), map_.map(), options_.constraints, out,
                nullptr, nullptr, threads);
      return;
    }
    // The newest scan's overlap and choice are reported as they were at its last association.
    ScanResult choice;
    localizer_.Associate(p_lidar, T_world_imu, CurrentTImuLidar(), map_.map(), nullptr, threads,
                         out, &p_lidar == newest_points ? r : &choice);
  };
  const WindowSolveReport report = window_->Optimize(associate);
  stats_.association_ms += report.association_ms;
  stats_.solve_ms += report.solve_ms;
  stats_.imu_factors_skipped = window_->stats().imu_factors_skipped;
  r->constraints = report.newest_constraints;
  r->iterations = report.iterations;
  r->rv = report.newest_rv;
  const DegeneracyMethod method = options_.degeneracy.method;
  r->degeneracy = method == DegeneracyMethod::kRv || method == DegeneracyMethod::kNone
                      ? DegeneracyReportFromRv(method, report.newest_rv,
                                               report.newest_position_information)
                      : report.newest_degeneracy;
  if (options_.smoother.map_update == "newest" || !window_filled_)
    InsertIntoWorkingMap(window_->size() - 1, p_lidar_end_);
  stats_.diverged_resets += report.failures;  // each failed round was restored
  if (!report.ok) return ScanStatus::kDiverged;
  // What the newest state's constraints leave after the solve (divergence monitor).
  const int newest = window_->size() - 1;
  const ResidualStats residuals = ComputeResidualStats(
      window_->constraints(newest), window_->state(newest).pose.ToPose3(), CurrentTImuLidar());
  if (residuals.count > 0) {
    r->health.residual_median_m = residuals.median_abs_m;
    r->health.residual_rms_m = residuals.rms_m;
  }
  if (report.newest_constraints < kMinPoseConstraints) {
    ++stats_.predict_only;
    return ScanStatus::kPredictOnly;
  }
  return ScanStatus::kUpdated;
}

bool SmootherOdometry::StartInReference(ImuKinematics* predicted) {
  const Pose3 T_world_imu(predicted->R_world_imu, predicted->p_world_imu);
  StatusOr<Pose3> T_ref_world =
      localizer_.Start(predicted->t_ns, p_lidar_end_, T_world_imu, CurrentTImuLidar());
  if (!T_ref_world.ok()) {
    status_ = T_ref_world.status();
    return false;
  }
  const Pose3& T = *T_ref_world;
  predicted->R_world_imu = T.R * predicted->R_world_imu;
  predicted->p_world_imu = T * predicted->p_world_imu;
  predicted->v_world_imu = T.R * predicted->v_world_imu;
  window_options_.g_world = T.R * window_options_.g_world;
  window_ = std::make_unique<SlidingWindow>(window_options_);  // still empty: gravity of the new frame
  return true;
}

void SmootherOdometry::InsertIntoWorkingMap(int k, const std::vector<Eigen::Vector3d>& p_lidar) {
  map_.InsertScan(window_->state(k).t_ns, window_->ScanTimeImuPose(k), CurrentTImuLidar(), p_lidar);
}

// The oldest state leaves the window: its points enter the output map (and,
// with map_update = marginalized, the working map) at its final estimate.
void SmootherOdometry::MarginalizeIfFull() {
  const double start_ms = ThreadCpuMs();
  std::optional<MarginalizedScan> m = window_->MarginalizeIfFull();
  if (!m) return;
  stats_.marginalization_ms += ThreadCpuMs() - start_ms;
  window_filled_ = true;
  if (options_.smoother.map_update == "marginalized") {
    InsertIntoOutputMap(m->state.t_ns, map_.InsertScan(m->state.t_ns, m->scan_T_world_imu,
                                                       CurrentTImuLidar(), m->p_lidar));
  } else {
    TransformPoints(m->scan_T_world_imu * CurrentTImuLidar(), m->p_lidar, &p_world_);
    InsertIntoOutputMap(m->state.t_ns, p_world_);
  }
  stats_.marginalization_failures = window_->stats().marginalization_failures;
}

// Entries of states older than this one left the window unmarginalized: dropped.
void SmootherOdometry::InsertIntoOutputMap(TimeNs state_t_ns,
                                           const std::vector<Eigen::Vector3d>& p_world) {
  while (!pending_.empty() && pending_.front().t_ns < state_t_ns) pending_.pop_front();
  RVLIO_CHECK_MSG(!pending_.empty() && pending_.front().t_ns == state_t_ns,
                  "smoother: a window state without its scan's returns");
  output_map_.InsertScan(p_world, pending_.front().returns, pending_.front().scan_index);
  pending_.pop_front();
}

Pose3 SmootherOdometry::CurrentTImuLidar() const {
  return window_ ? window_->T_imu_lidar() : T_imu_lidar_;
}

void SmootherOdometry::ReportExtrinsic(ScanResult* r) {
  if (!options_.smoother.estimate_extrinsics) return;
  window_->CountExcitationScan();
  r->T_imu_lidar = window_->T_imu_lidar();
  stats_.extrinsic =
      MakeExtrinsicReport(window_->extrinsic_excitation(), T_imu_lidar_, window_->T_imu_lidar());
  stats_.extrinsic.map_rebuilds = map_.rebuilds();
}

TimeNs SmootherOdometry::ScanTimeShiftNs() const {
  if (!options_.lidar.estimate_time_offset || !window_) return 0;
  return SecondsToNs(window_->time_offset_s() - options_.lidar.time_offset);
}

void SmootherOdometry::ReportTimeOffset(ScanResult* r, const ImuPoseHistory& history) {
  if (!options_.lidar.estimate_time_offset || !window_) return;
  time_offset_excitation_.CountScan(newest_.t_ns, MotionAtEnd(history).gyro_imu,
                                    newest_.v_world_imu);
  r->time_offset_s = window_->time_offset_s();
  r->time_offset_std_s = window_->time_offset_std_s();
  UpdateTimeOffsetReport(time_offset_excitation_, options_.lidar, window_->time_offset_s(),
                         window_->time_offset_std_s(), window_->time_offset_at_bound(),
                         newest_.t_ns, &stats_.time_offset);
}

void SmootherOdometry::SetNewestFromWindow() {
  const WindowState s = window_->state(window_->size() - 1);
  newest_.t_ns = s.t_ns;
  newest_.R_world_imu = s.pose.q_world_imu.normalized().toRotationMatrix();
  newest_.p_world_imu = s.pose.p_world_imu;
  newest_.v_world_imu = s.speed_bias.v_world_imu;
  bg_ = s.speed_bias.bg;
  ba_ = s.speed_bias.ba;
}

std::vector<std::string> SmootherOdometry::warnings() const {
  std::vector<std::string> w = warnings_;
  for (std::string& q : StatsWarnings(stats_)) w.push_back(std::move(q));
  const auto count = [&w](int64_t n, const std::string& what) {
    if (n > 0) w.push_back(std::to_string(n) + " " + what);
  };
  count(stats_.imu_factors_skipped,
        "window states without an IMU factor (IMU gap longer than imu.max_gap or a zero "
        "interval): a weak velocity/bias continuity prior was used instead");
  count(stats_.diverged_resets,
        "window solves failed or diverged: the last good window state was restored");
  count(stats_.marginalization_failures,
        "marginalizations failed: the window was re-anchored with a prior at its oldest state");
  count(stats_.imu_non_finite, "non-finite IMU samples were dropped");
  return w;
}

}  // namespace rvlio

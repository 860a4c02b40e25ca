// The sliding-window smoother as a backend of the odometry pipeline.
#include "rvlio/odometry/smoother_backend.h"

#include <optional>
#include <utility>

#include "rvlio/common/cpu_time.h"
#include "rvlio/common/parallel.h"
#include "rvlio/constraints/plane_association.h"
#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/imu/noise.h"
#include "rvlio/imu/preintegration.h"
#include "rvlio/lidar/extrinsics.h"

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

// The buffered samples from the last one at or before t0_ns to the first
// one at or after t1_ns.
std::vector<ImuSample> ImuCovering(const std::deque<ImuSample>& imu, TimeNs t0_ns, TimeNs t1_ns) {
  std::vector<ImuSample> samples;
  for (const ImuSample& s : imu) {
    if (!samples.empty() && s.t_ns <= t0_ns) samples.clear();  // keep the last one <= t0
    samples.push_back(s);
    if (s.t_ns >= t1_ns) break;
  }
  return samples;
}

// Consecutive samples around or inside [t0, t1] farther apart than
// max_gap_ns (imu.max_gap; or [t0, t1] not covered): the preintegration
// would bridge a stretch without measurements. `samples`: from
// ImuCovering(t0, t1).
bool HasImuGap(const std::vector<ImuSample>& samples, TimeNs t0_ns, TimeNs t1_ns,
               TimeNs max_gap_ns) {
  if (samples.empty()) return true;
  if (samples.front().t_ns - t0_ns > max_gap_ns || t1_ns - samples.back().t_ns > max_gap_ns)
    return true;
  for (size_t i = 1; i < samples.size(); ++i)
    if (samples[i].t_ns - samples[i - 1].t_ns > max_gap_ns) return true;
  return false;
}

// Keeps the last sample at or before t_ns and those after it.
void DropImuBefore(TimeNs t_ns, std::deque<ImuSample>* imu) {
  while (imu->size() >= 2 && (*imu)[1].t_ns <= t_ns) imu->pop_front();
}

}  // namespace

SmootherBackend::SmootherBackend(const OdometryOptions& options)
    : options_(options),
      window_options_(MakeWindowOptions(options)),
      T_imu_lidar_(ImuTLidar(options.extrinsics)) {}

// Gravity, gyro bias, zero velocity, identity yaw at the origin; the sample
// that ended the static start stays buffered: the signal at the start of
// the first interval.
void SmootherBackend::Initialize(const StaticAlignment& a, const ImuSample& imu,
                                 std::deque<ImuSample>* imu_buffer) {
  newest_.t_ns = imu.t_ns;
  newest_.R_world_imu = a.R_world_imu;
  bg_ = a.gyro_bias;
  window_options_.g_world = a.g_world;
  window_ = std::make_unique<SlidingWindow>(window_options_);
  imu_buffer->push_back(imu);
}

Prediction SmootherBackend::Predict(std::deque<ImuSample>* imu_buffer, TimeNs t_end_ns) {
  DropImuBefore(newest_.t_ns, imu_buffer);
  samples_ = ImuCovering(*imu_buffer, newest_.t_ns, t_end_ns);
  history_ = ImuPoseHistory::Integrate(newest_, samples_, t_end_ns, bg_, ba_,
                                       window_options_.g_world);
  Prediction p;
  p.at_end = history_.Newest();
  p.poses = &history_.samples();
  p.mean_imu = MeanImu(samples_, newest_.t_ns, t_end_ns);
  return p;
}

void SmootherBackend::ChangeWorldFrame(const Pose3& T_ref_world, Prediction* prediction) {
  ImuKinematics& x = prediction->at_end;
  x.R_world_imu = T_ref_world.R * x.R_world_imu;
  x.p_world_imu = T_ref_world * x.p_world_imu;
  x.v_world_imu = T_ref_world.R * x.v_world_imu;
  window_options_.g_world = T_ref_world.R * window_options_.g_world;
  window_ = std::make_unique<SlidingWindow>(window_options_);  // still empty: gravity of the new frame
}

// With a reference map the first scan was aligned to it (ReferenceLocalizer::Start).
ScanStatus SmootherBackend::Update(ScanContext& scan, ScanResult* r) {
  const ScanStatus status = window_->empty() ? StartWindow(scan) : UpdateWindow(scan, r);
  if (scan.localizer->enabled() && status == ScanStatus::kMapInit) {
    r->map_overlap = scan.localizer->start_overlap();
    r->localized = true;
  }
  SetNewestFromWindow();
  return status;
}

// The first scan: the first window state (with the prior of the static
// initialization) at the predicted pose; its points start the map (Insert).
ScanStatus SmootherBackend::StartWindow(ScanContext& scan) {
  const ImuKinematics& predicted = scan.prediction->at_end;
  window_->Start(scan.t_ns,
                 PoseBlock(Eigen::Quaterniond(predicted.R_world_imu), predicted.p_world_imu),
                 SpeedBiasBlock{predicted.v_world_imu, bg_, ba_}, *scan.p_lidar);
  return ScanStatus::kMapInit;
}

// Adds the scan's state (IMU factor from the newest state unless the interval
// is empty or has a gap) and optimizes the window.
ScanStatus SmootherBackend::UpdateWindow(ScanContext& scan, ScanResult* r) {
  const ImuKinematics& predicted = scan.prediction->at_end;
  const TimeNs t_ns = scan.t_ns;
  std::optional<ImuPreintegration> imu;
  if (t_ns > newest_.t_ns &&
      !HasImuGap(samples_, newest_.t_ns, t_ns, SecondsToNs(options_.imu.max_gap)))
    imu = ImuPreintegration::FromSamples(samples_, newest_.t_ns, t_ns,
                                         ImuNoise::FromOptions(options_.imu), bg_, ba_);
  window_->Add(t_ns, PoseBlock(Eigen::Quaterniond(predicted.R_world_imu), predicted.p_world_imu),
               SpeedBiasBlock{predicted.v_world_imu, bg_, ba_}, std::move(imu), *scan.p_lidar,
               MotionAtEnd(history_));
  const std::vector<Eigen::Vector3d>* newest_points = &window_->points(window_->size() - 1);
  const WorkingMap& map = *scan.map;
  const ReferenceLocalizer& localizer = *scan.localizer;
  const ScanAssociateFn associate = [this, newest_points, r, &map, &localizer](
                                        const std::vector<Eigen::Vector3d>& p_lidar,
                                        const Pose3& T_world_imu, ConstraintList* out) {
    const int threads = ResolveThreads(options_.constraints.threads);
    if (!localizer.enabled()) {
      Associate(p_lidar, T_world_imu, T_imu_lidar(), map.map(), options_.constraints, out,
                nullptr, nullptr, threads);
      return;
    }
    // The newest scan's overlap and choice are reported as they were at its last association.
    ScanResult choice;
    localizer.Associate(p_lidar, T_world_imu, T_imu_lidar(), map.map(), nullptr, threads, out,
                        &p_lidar == newest_points ? r : &choice);
  };
  const WindowSolveReport report = window_->Optimize(associate);
  OdometryStats& stats = *scan.stats;
  stats.association_ms += report.association_ms;
  stats.solve_ms += report.solve_ms;
  stats.imu_factors_skipped = window_->stats().imu_factors_skipped;
  r->constraints = report.newest_constraints;
  r->iterations = report.iterations;
  r->rv = report.newest_rv;
  const DegeneracyMethod method = options_.degeneracy.method;
  r->degeneracy = method == DegeneracyMethod::kRv || method == DegeneracyMethod::kNone
                      ? DegeneracyReportFromRv(method, report.newest_rv,
                                               report.newest_position_information)
                      : report.newest_degeneracy;
  stats.diverged_resets += report.failures;  // each failed round was restored
  if (!report.ok) return ScanStatus::kDiverged;
  // What the newest state's constraints leave after the solve (divergence monitor).
  const int newest = window_->size() - 1;
  const ResidualStats residuals = ComputeResidualStats(
      window_->constraints(newest), window_->state(newest).pose.ToPose3(), T_imu_lidar());
  if (residuals.count > 0) {
    r->health.residual_median_m = residuals.median_abs_m;
    r->health.residual_rms_m = residuals.rms_m;
  }
  if (report.newest_constraints < kMinPoseConstraints) {
    ++stats.predict_only;
    return ScanStatus::kPredictOnly;
  }
  return ScanStatus::kUpdated;
}

// smoother.map_update = newest, or while the window fills for the first
// time: the newest scan enters the working map right after its first solve
// (whatever the solve's outcome). Then the oldest state leaves a full window.
void SmootherBackend::Insert(ScanContext& scan) {
  if (options_.smoother.map_update == "newest" || !window_filled_)
    InsertIntoWorkingMap(window_->size() - 1, *scan.p_lidar, scan.map);
  MarginalizeIfFull(scan);
}

void SmootherBackend::Finish(ScanContext& scan) {
  for (int k = 0; k < window_->size(); ++k) {
    TransformPoints(window_->ScanTimeImuPose(k) * T_imu_lidar(), window_->points(k), &p_world_);
    scan.output->Insert(window_->state(k).t_ns, p_world_);
  }
}

void SmootherBackend::InsertIntoWorkingMap(int k, const std::vector<Eigen::Vector3d>& p_lidar,
                                           WorkingMap* map) {
  map->InsertScan(window_->state(k).t_ns, window_->ScanTimeImuPose(k), T_imu_lidar(), p_lidar);
}

// The oldest state leaves the window: its points enter the output map (and,
// with map_update = marginalized, the working map) at its final estimate.
void SmootherBackend::MarginalizeIfFull(ScanContext& scan) {
  const double start_ms = ThreadCpuMs();
  std::optional<MarginalizedScan> m = window_->MarginalizeIfFull();
  if (!m) return;
  scan.stats->marginalization_ms += ThreadCpuMs() - start_ms;
  window_filled_ = true;
  if (options_.smoother.map_update == "marginalized") {
    scan.output->Insert(m->state.t_ns, scan.map->InsertScan(m->state.t_ns, m->scan_T_world_imu,
                                                            T_imu_lidar(), m->p_lidar));
  } else {
    TransformPoints(m->scan_T_world_imu * T_imu_lidar(), m->p_lidar, &p_world_);
    scan.output->Insert(m->state.t_ns, p_world_);
  }
  scan.stats->marginalization_failures = window_->stats().marginalization_failures;
}

void SmootherBackend::SetNewestFromWindow() {
  const WindowState s = window_->state(window_->size() - 1);
  newest_.t_ns = s.t_ns;
  newest_.R_world_imu = s.pose.q_world_imu.normalized().toRotationMatrix();
  newest_.p_world_imu = s.pose.p_world_imu;
  newest_.v_world_imu = s.speed_bias.v_world_imu;
  bg_ = s.speed_bias.bg;
  ba_ = s.speed_bias.ba;
}

Pose3 SmootherBackend::T_imu_lidar() const {
  return window_ ? window_->T_imu_lidar() : T_imu_lidar_;
}

double SmootherBackend::time_offset_s() const {
  return window_ ? window_->time_offset_s() : options_.lidar.time_offset;
}

void SmootherBackend::ReportPropagationState(ScanResult* r) const {
  r->bg_imu = bg_;
  r->ba_imu = ba_;
  r->g_world = window_options_.g_world;
}

std::vector<std::string> SmootherBackend::Warnings(const OdometryStats& stats) const {
  std::vector<std::string> w;
  const auto count = [&w](int64_t n, const std::string& what) {
    if (n > 0) w.push_back(std::to_string(n) + " " + what);
  };
  count(stats.imu_factors_skipped,
        "window states without an IMU factor (IMU gap longer than imu.max_gap or a zero "
        "interval): a weak velocity/bias continuity prior was used instead");
  count(stats.diverged_resets,
        "window solves failed or diverged: the last good window state was restored");
  count(stats.marginalization_failures,
        "marginalizations failed: the window was re-anchored with a prior at its oldest state");
  count(stats.imu_non_finite, "non-finite IMU samples were dropped");
  return w;
}

}  // namespace rvlio

#include "rvlio/odometry/scan_frontend.h"

#include <cmath>
#include <cstdio>
#include <utility>

#include "rvlio/math/so3.h"
#include "rvlio/refine/refine_states.h"

namespace rvlio {
namespace {

constexpr int kRemoveFarEveryScans = 10;  // working-map trimming period

}  // namespace

std::optional<StaticAlignment> StaticInitializer::Add(const ImuSample& imu) {
  samples_.push_back(imu);
  if (imu.t_ns - samples_.front().t_ns < duration_ns_) return std::nullopt;
  const StaticAlignment a = AlignStatic(samples_);
  samples_.clear();
  return a;
}

std::string MovingStartWarning(const StaticAlignment& a) {
  if (!a.moving) return "";
  return "the sequence starts moving (acc std " + std::to_string(a.acc_std) + " m/s^2, gyro std " +
         std::to_string(a.gyro_std) + " rad/s); initialized from the mean IMU values";
}

void TransformPoints(const Pose3& T_world_lidar, const std::vector<Eigen::Vector3d>& p_lidar,
                     std::vector<Eigen::Vector3d>* p_world) {
  p_world->resize(p_lidar.size());
  for (size_t i = 0; i < p_lidar.size(); ++i) (*p_world)[i] = T_world_lidar * p_lidar[i];
}

WorkingMap::WorkingMap(const MapOptions& options, bool reanchor)
    : reanchor_(reanchor && options.reanchor_window > 0.0), map_(options) {}

const std::vector<Eigen::Vector3d>& WorkingMap::InsertScan(
    TimeNs t_ns, const Pose3& T_world_imu, const Pose3& T_imu_lidar,
    const std::vector<Eigen::Vector3d>& p_lidar) {
  if (reanchor_) {
    if (!T_imu_lidar_built_) T_imu_lidar_built_ = T_imu_lidar;
    ReanchorIfMoved(T_imu_lidar);
    kept_.push_back({t_ns, T_world_imu, p_lidar});
    while (kept_.front().t_ns < t_ns - SecondsToNs(map_.options().reanchor_window)) kept_.pop_front();
  }
  const Pose3 T_world_lidar = T_world_imu * T_imu_lidar;
  TransformPoints(T_world_lidar, p_lidar, &p_world_);
  Insert(p_world_, T_world_lidar.t);
  return p_world_;
}

bool WorkingMap::ReanchorIfMoved(const Pose3& T_imu_lidar) {
  if (!reanchor_ || kept_.empty() || !ExtrinsicMoved(T_imu_lidar)) return false;
  Rebuild(T_imu_lidar);
  return true;
}

void WorkingMap::Insert(const std::vector<Eigen::Vector3d>& p_world,
                        const Eigen::Vector3d& sensor_world) {
  map_.Insert(p_world);
  if (++scans_since_trim_ >= kRemoveFarEveryScans) {
    map_.RemoveFar(sensor_world, map_.options().working_radius);
    scans_since_trim_ = 0;
  }
}

bool WorkingMap::ExtrinsicMoved(const Pose3& T_imu_lidar) const {
  const double rotation_rad = so3::Log(T_imu_lidar_built_->R.transpose() * T_imu_lidar.R).norm();
  return rotation_rad > map_.options().reanchor_rotation * M_PI / 180.0 ||
         (T_imu_lidar.t - T_imu_lidar_built_->t).norm() > map_.options().reanchor_translation;
}

// The map again from the kept scans only, each at its IMU pose with T_imu_lidar.
void WorkingMap::Rebuild(const Pose3& T_imu_lidar) {
  map_.Clear();
  for (const KeptScan& k : kept_) {
    TransformPoints(k.T_world_imu * T_imu_lidar, k.p_lidar, &p_world_);
    map_.Insert(p_world_);
  }
  T_imu_lidar_built_ = T_imu_lidar;
  ++rebuilds_;
}

std::string TimeOffsetAtBoundWarning(const LidarOptions& lidar, TimeNs t_ns) {
  return "the estimated LiDAR-IMU time offset reached lidar.time_offset_max (" +
         std::to_string(lidar.time_offset_max) + " s) at t=" + std::to_string(NsToSeconds(t_ns)) +
         " s and is held there: the clocks differ by more, or the estimate is lost; check the "
         "recording with `rvlio calibrate-time` and set lidar.time_offset";
}

ReferenceLocalizer::ReferenceLocalizer(Localization localization,
                                       const LocalizationOptions& options,
                                       const ConstraintOptions& constraints)
    : localization_(std::move(localization)), options_(options), constraints_(constraints) {}

namespace {

std::string Vec(const Eigen::Vector3d& v, int digits) {
  char text[96];
  std::snprintf(text, sizeof(text), "(%.*f, %.*f, %.*f)", digits, v.x(), digits, v.y(), digits,
                v.z());
  return text;
}

// Another candidate as good as the best (within search_ambiguity of its
// overlap) but elsewhere (more than 1 m or 10 degrees away), or null.
const ReferenceAlignment* RivalOf(const std::vector<ReferenceAlignment>& candidates,
                                  double ambiguity) {
  constexpr double kDistinctM = 1.0, kDistinctRad = 10.0 * M_PI / 180.0;
  const ReferenceAlignment& best = candidates.front();
  for (size_t i = 1; i < candidates.size(); ++i) {
    const ReferenceAlignment& c = candidates[i];
    if (c.overlap < best.overlap - ambiguity) break;  // sorted by overlap
    if ((c.T_ref_imu.t - best.T_ref_imu.t).norm() > kDistinctM ||
        so3::Log(c.T_ref_imu.R.transpose() * best.T_ref_imu.R).norm() > kDistinctRad)
      return &c;
  }
  return nullptr;
}

}  // namespace

// From the initial pose (interpolated at t_ns when there are several).
StatusOr<ReferenceAlignment> ReferenceLocalizer::AlignFromInitialPose(
    TimeNs t_ns, const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_imu_lidar) const {
  const Trajectory& initial = localization_.initial_poses;
  Pose3 T_ref_imu_guess(initial.front().q_world_imu, initial.front().p_world_imu);
  if (initial.size() > 1 && !InterpolatePose(initial, t_ns, &T_ref_imu_guess)) {
    char text[160];
    std::snprintf(text, sizeof(text), "the initial poses (%.3f to %.3f s) do not cover the first "
                  "scan's time %.3f s", NsToSeconds(initial.front().t_ns),
                  NsToSeconds(initial.back().t_ns), NsToSeconds(t_ns));
    return Status::InvalidInput(text);
  }
  const ReferenceAlignment a = AlignToReference(p_lidar, T_imu_lidar, *localization_.reference,
                                                T_ref_imu_guess, constraints_, options_);
  if (!(a.overlap >= options_.min_start_overlap))
    return Status::InvalidInput(
        "the first scan does not match the reference map at the initial pose (" +
        std::to_string(static_cast<int>(std::lround(100.0 * a.overlap))) +
        " % of its points on reference planes after alignment, localization.min_start_overlap " +
        std::to_string(options_.min_start_overlap) +
        "): check --initial-pose and that the map is in the same frame and in metres");
  return a;
}

// Without an initial pose: the global search, refused when nothing matches
// or when two distinct places match as well.
StatusOr<ReferenceAlignment> ReferenceLocalizer::SearchStart(
    const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_world_imu,
    const Pose3& T_imu_lidar) const {
  const std::vector<ReferenceAlignment> candidates = SearchReference(
      p_lidar, T_imu_lidar, *localization_.reference, T_world_imu.R, constraints_, options_);
  if (candidates.empty() || !(candidates.front().overlap >= options_.min_start_overlap))
    return Status::InvalidInput(
        "no place in the reference map matches the first scan (global search); check that the "
        "map is in metres and covers the start, or give --initial-pose");
  // Positions in the message are in the map's frame, as the user gave it.
  const LocalOrigin& origin = localization_.origin;
  if (const ReferenceAlignment* rival = RivalOf(candidates, options_.search_ambiguity))
    return Status::InvalidInput(
        "the first scan matches the reference map equally well at " +
        Vec(origin.ToUser(candidates.front().T_ref_imu.t), 2) + " and at " +
        Vec(origin.ToUser(rival->T_ref_imu.t), 2) +
        " (global search): give --initial-pose");
  return candidates.front();
}

StatusOr<Pose3> ReferenceLocalizer::Start(TimeNs t_ns, const std::vector<Eigen::Vector3d>& p_lidar,
                                          const Pose3& T_world_imu, const Pose3& T_imu_lidar) {
  const bool guided = !localization_.initial_poses.empty();
  StatusOr<ReferenceAlignment> a = guided ? AlignFromInitialPose(t_ns, p_lidar, T_imu_lidar)
                                          : SearchStart(p_lidar, T_world_imu, T_imu_lidar);
  if (!a.ok()) return a.status();
  if (a->weakest_axis_constraints < options_.min_start_axis_constraints &&
      !(guided && options_.trust_initial_pose)) {
    char text[160];
    std::snprintf(text, sizeof(text), " (as %.1f constraints along it, "
                  "localization.min_start_axis_constraints %g): featureless there",
                  a->weakest_axis_constraints, options_.min_start_axis_constraints);
    return Status::InvalidInput(
        "the first scan does not fix the start along " + Vec(a->weakest_axis, 2) +
        " in the reference" + text +
        (guided ? ", so --initial-pose cannot be checked along it; start where the map has "
                  "features, or set localization.trust_initial_pose=true"
                : "; give --initial-pose"));
  }
  started_ = true;
  start_overlap_ = a->overlap;
  return a->T_ref_imu * T_world_imu.Inverse();
}

const VoxelMap& ReferenceLocalizer::Associate(const std::vector<Eigen::Vector3d>& p_lidar,
                                              const Pose3& T_world_imu, const Pose3& T_imu_lidar,
                                              const VoxelMap& working, AssociationCache* cache,
                                              int threads, ConstraintList* out,
                                              ScanResult* r) const {
  AssociationStats stats;
  rvlio::Associate(p_lidar, T_world_imu, T_imu_lidar, *localization_.reference,
                   constraints_, out, &stats, cache, threads);
  r->map_overlap = p_lidar.empty() ? 0.0 : static_cast<double>(stats.num_accepted) /
                                               static_cast<double>(p_lidar.size());
  r->localized = *r->map_overlap >= options_.min_overlap || working.Empty();
  if (r->localized) return *localization_.reference;
  if (cache != nullptr) cache->Reset();
  rvlio::Associate(p_lidar, T_world_imu, T_imu_lidar, working, constraints_, out, nullptr, cache,
                   threads);
  return working;
}

bool AcceptImu(const ImuSample& imu, const std::deque<ImuSample>& buffer, TimeNs max_gap_ns,
               OdometryStats* stats) {
  if (!imu.acc_imu.allFinite() || !imu.gyro_imu.allFinite()) {
    ++stats->imu_non_finite;
    return false;
  }
  if (!buffer.empty() && imu.t_ns - buffer.back().t_ns > max_gap_ns)
    ++stats->imu_gaps_over_scan;
  return true;
}

void ScanQueue::Add(Scan scan, bool initialized, TimeNs state_time_ns, OdometryStats* stats) {
  ++stats->scans_received;
  if (initialized && scan.t_end_ns <= last_end_ns_) {
    ++stats->scans_out_of_order;  // estimating it would step the trajectory back in time
    return;
  }
  if (!initialized || scan.t_start_ns < state_time_ns) {
    ++stats->scans_before_imu;  // no IMU state covers this scan
    return;
  }
  last_end_ns_ = scan.t_end_ns;
  scans_.push_back(std::move(scan));
}

void ScanQueue::DropPastImu(TimeNs max_gap_ns, OdometryStats* stats) {
  if (imu_end_ns_ == std::numeric_limits<TimeNs>::min()) return;  // no IMU: nothing was queued
  while (!scans_.empty() && scans_.back().t_end_ns - imu_end_ns_ > max_gap_ns) {
    scans_.pop_back();
    ++stats->scans_after_imu;
  }
}

std::vector<std::string> QueueWarnings(const OdometryStats& stats) {
  std::vector<std::string> w;
  if (stats.scans_out_of_order > 0)
    w.push_back(std::to_string(stats.scans_out_of_order) +
                " scans were skipped: their stamps repeat or go back behind a scan already taken "
                "(stats.scans_out_of_order)");
  if (stats.scans_after_imu > 0)
    w.push_back(std::to_string(stats.scans_after_imu) +
                " scans at the end were skipped: they end more than imu.max_gap after the last "
                "IMU sample (the IMU stopped before the LiDAR, or lidar.time_offset is wrong; "
                "stats.scans_after_imu)");
  return w;
}

void ScanQueue::DropStartingBefore(TimeNs state_time_ns, OdometryStats* stats) {
  while (!scans_.empty() && scans_.front().t_start_ns < state_time_ns) {
    scans_.pop_front();
    ++stats->scans_before_imu;
  }
}

Scan ScanQueue::PopFront() {
  Scan scan = std::move(scans_.front());
  scans_.pop_front();
  return scan;
}

}  // namespace rvlio

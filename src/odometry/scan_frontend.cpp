#include "rvlio/odometry/scan_frontend.h"

#include <cmath>
#include <cstdio>
#include <utility>

#include "rvlio/math/so3.h"
#include "rvlio/math/pose_interpolation.h"

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

ReferenceLocalizer::ReferenceLocalizer(Localization localization,
                                       const LocalizationOptions& options,
                                       const ConstraintOptions& constraints)
    : localization_(std::move(localization)), options_(options), constraints_(constraints) {}

// From the initial pose (interpolated at t_ns when there are several), or by
// the global search without one; judged by FindStartInReference.
StatusOr<Pose3> ReferenceLocalizer::Start(TimeNs t_ns, const std::vector<Eigen::Vector3d>& p_lidar,
                                          const Pose3& T_world_imu, const Pose3& T_imu_lidar) {
  const Trajectory& initial = localization_.initial_poses;
  std::optional<Pose3> guess;
  if (!initial.empty()) {
    guess = Pose3(initial.front().q_world_imu, initial.front().p_world_imu);
    if (initial.size() > 1 && !InterpolatePose(initial, t_ns, &*guess)) {
      char text[160];
      std::snprintf(text, sizeof(text), "the initial poses (%.3f to %.3f s) do not cover the "
                    "first scan's time %.3f s", NsToSeconds(initial.front().t_ns),
                    NsToSeconds(initial.back().t_ns), NsToSeconds(t_ns));
      return Status::InvalidInput(text);
    }
  }
  StatusOr<ReferenceAlignment> a =
      FindStartInReference(p_lidar, T_imu_lidar, *localization_.reference,
                           guess ? &*guess : nullptr, T_world_imu.R, constraints_, options_,
                           "--initial-pose", localization_.origin);
  if (!a.ok()) return a.status();
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
  const StampVerdict verdict = screen_.Judge({scan.t_start_ns, scan.t_end_ns}, imu_end_ns_);
  if (verdict == StampVerdict::kOutOfOrder) {
    ++stats->scans_out_of_order;  // estimating it would step the trajectory back in time
    return;
  }
  if (verdict == StampVerdict::kNewestWereAhead) {
    const std::vector<ScanSpan>& dropped = screen_.dropped();
    for (auto s = dropped.rbegin(); s != dropped.rend(); ++s) DropAhead(s->end_ns, stats);  // newest first
  }
  if (!initialized || scan.t_start_ns < state_time_ns) {
    ++stats->scans_before_imu;  // no IMU state covers this scan
    before_imu_ends_ns_.push_back(scan.t_end_ns);
    if (before_imu_ends_ns_.size() > ScanStampScreen::kRecent) before_imu_ends_ns_.pop_front();
    return;
  }
  scans_.push_back(std::move(scan));
}

// A scan stamped ahead is still queued (at the back: it waits for the IMU to
// reach its end), or was counted before the IMU; one already estimated
// stays (the scans behind its stamp then fall before the state and are
// skipped as such).
void ScanQueue::DropAhead(TimeNs end_ns, OdometryStats* stats) {
  const auto before = std::find(before_imu_ends_ns_.begin(), before_imu_ends_ns_.end(), end_ns);
  if (!scans_.empty() && scans_.back().t_end_ns == end_ns) {
    scans_.pop_back();
  } else if (before != before_imu_ends_ns_.end()) {
    before_imu_ends_ns_.erase(before);
    --stats->scans_before_imu;
  } else {
    return;
  }
  ++stats->scans_stamp_ahead;
}

std::optional<Scan> ScanQueue::PopFrontShifted(TimeNs shift_ns, TimeNs state_time_ns,
                                               OdometryStats* stats) {
  Scan scan = PopFront();
  if (shift_ns != 0) ShiftScanTime(shift_ns, &scan);
  if (scan.t_end_ns > state_time_ns) return scan;
  ++stats->scans_out_of_order;
  return std::nullopt;
}

void ScanQueue::DropPastImu(TimeNs max_gap_ns, OdometryStats* stats) {
  if (imu_end_ns_ == ScanStampScreen::kNoImu) return;  // no IMU: nothing was queued
  while (!scans_.empty() && scans_.back().t_end_ns - imu_end_ns_ > max_gap_ns) {
    scans_.pop_back();
    ++stats->scans_after_imu;
  }
}

std::vector<std::string> StatsWarnings(const OdometryStats& stats) {
  std::vector<std::string> w;
  if (stats.scans_out_of_order > 0)
    w.push_back(std::to_string(stats.scans_out_of_order) +
                " scans were skipped: their stamps repeat or go back behind a scan already taken "
                "(stats.scans_out_of_order)");
  if (stats.scans_stamp_ahead > 0)
    w.push_back(std::to_string(stats.scans_stamp_ahead) +
                " scans were skipped: their stamps jumped ahead, at least a scan period past the "
                "scan after them and past the IMU, which the scans after them follow "
                "(stats.scans_stamp_ahead)");
  if (stats.scans_after_imu > 0)
    w.push_back(std::to_string(stats.scans_after_imu) +
                " scans at the end were skipped: they end more than imu.max_gap after the last "
                "IMU sample (the IMU stopped before the LiDAR, or lidar.time_offset is wrong; "
                "stats.scans_after_imu)");
  for (std::string& t : TimeOffsetWarnings(stats.time_offset)) w.push_back(std::move(t));
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

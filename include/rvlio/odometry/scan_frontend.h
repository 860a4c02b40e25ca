#pragma once
// Pieces of the odometry's backbone (odometry/pipeline.h) shared by its
// backends: the extrinsics, static initialization and the working
// map with its periodic trim (the IMU poses for deskew: imu/pose_history.h).
#include <algorithm>
#include <deque>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/types.h"
#include "rvlio/constraints/plane_association.h"
#include "rvlio/imu/integrator.h"
#include "rvlio/imu/options.h"
#include "rvlio/imu/static_init.h"
#include "rvlio/lidar/deskew.h"
#include "rvlio/lidar/options.h"
#include "rvlio/lidar/preprocess.h"
#include "rvlio/lidar/scan_order.h"
#include "rvlio/map/options.h"
#include "rvlio/map/voxel_map.h"
#include "rvlio/math/pose.h"
#include "rvlio/odometry/odometry.h"
#include "rvlio/odometry/reference.h"

namespace rvlio {

// Collects IMU samples until they span init_duration_s, then aligns them
// (imu/static_init.h).
class StaticInitializer {
 public:
  explicit StaticInitializer(double init_duration_s) : duration_ns_(SecondsToNs(init_duration_s)) {}

  // Adds one sample. Once the collected samples span the init duration,
  // returns their alignment and forgets them; before that, nothing.
  std::optional<StaticAlignment> Add(const ImuSample& imu);

 private:
  TimeNs duration_ns_;
  std::vector<ImuSample> samples_;
};

// The warning for a start that does not look static (a.moving).
std::string MovingStartWarning(const StaticAlignment& a);

// p_world[i] = T_world_lidar * p_lidar[i].
void TransformPoints(const Pose3& T_world_lidar, const std::vector<Eigen::Vector3d>& p_lidar,
                     std::vector<Eigen::Vector3d>* p_world);

// The map scans are associated against: a VoxelMap whose voxels farther than
// map.working_radius from the sensor are removed every few insertions.
//
// Re-anchoring (on with online extrinsic estimation): a map point keeps the
// extrinsic it was inserted with, and a voxel keeps its first points, so a
// map built from a wrong start extrinsic holds the estimate back. With
// re-anchoring the map also keeps the scans of the last map.reanchor_window
// seconds (IMU pose and LiDAR points), and when the extrinsic has moved more
// than map.reanchor_rotation / reanchor_translation since the map was built,
// it is rebuilt from them with the current extrinsic before the next scan is
// inserted. The IMU poses are the anchor: a rebuilt map agrees with them and
// the new extrinsic, so the estimator's state stays as it is
// (docs/extrinsics.md "Map re-anchoring").
class WorkingMap {
 public:
  WorkingMap(const MapOptions& options, bool reanchor);

  // Re-anchoring: when T_imu_lidar has moved past the thresholds since the map
  // was built, rebuilds it from the kept scans, each at its IMU pose with
  // T_imu_lidar; true if it did.
  bool ReanchorIfMoved(const Pose3& T_imu_lidar);
  // Inserts one scan: p_lidar (LiDAR frame) placed at T_world_imu * T_imu_lidar,
  // after ReanchorIfMoved(T_imu_lidar) when re-anchoring is on. Returns the
  // inserted points in the world frame (valid until the next call).
  const std::vector<Eigen::Vector3d>& InsertScan(TimeNs t_ns, const Pose3& T_world_imu,
                                                 const Pose3& T_imu_lidar,
                                                 const std::vector<Eigen::Vector3d>& p_lidar);

  const VoxelMap& map() const { return map_; }
  bool Empty() const { return map_.Empty(); }
  int64_t rebuilds() const { return rebuilds_; }

 private:
  struct KeptScan {
    TimeNs t_ns;
    Pose3 T_world_imu;
    std::vector<Eigen::Vector3d> p_lidar;
  };
  void Insert(const std::vector<Eigen::Vector3d>& p_world, const Eigen::Vector3d& sensor_world);
  bool ExtrinsicMoved(const Pose3& T_imu_lidar) const;
  void Rebuild(const Pose3& T_imu_lidar);

  bool reanchor_;
  VoxelMap map_;
  int scans_since_trim_ = 0;
  std::deque<KeptScan> kept_;
  std::optional<Pose3> T_imu_lidar_built_;  // the extrinsic the map was (re)built with
  int64_t rebuilds_ = 0;
  std::vector<Eigen::Vector3d> p_world_;
};

// The reference-map side of both backends (odometry/reference.h): the start
// alignment and, per scan, the choice between the reference and the working
// map. Disabled (and never consulted) without a reference.
class ReferenceLocalizer {
 public:
  ReferenceLocalizer(Localization localization, const LocalizationOptions& options,
                     const ConstraintOptions& constraints);

  bool enabled() const { return localization_.reference != nullptr; }
  bool started() const { return started_; }
  double start_overlap() const { return start_overlap_; }  // of the aligned first scan
  // The first scan, ending at t_ns: aligns p_lidar (deskewed, LiDAR frame)
  // to the reference from the initial pose, or by the global search without
  // one, and judges the start (FindStartInReference). Returns T_ref_world,
  // the change of world frame that takes the estimator's current T_world_imu
  // to the aligned pose, or InvalidInput when the initial poses do not cover
  // t_ns or the start is refused (naming --initial-pose or the map).
  StatusOr<Pose3> Start(TimeNs t_ns, const std::vector<Eigen::Vector3d>& p_lidar,
                        const Pose3& T_world_imu, const Pose3& T_imu_lidar);
  // Associates a scan at T_world_imu (threads as AssociateWith's): with the
  // reference when its overlap there reaches localization.min_overlap, else
  // with `working`. Returns the map used; sets r->map_overlap and
  // r->localized. With a cache (may be null), a later association at the
  // same pose reuses the planes of the map used.
  const VoxelMap& Associate(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_world_imu,
                            const Pose3& T_imu_lidar, const VoxelMap& working,
                            AssociationCache* cache, int threads, ConstraintList* out,
                            ScanResult* r) const;

 private:
  Localization localization_;
  LocalizationOptions options_;
  ConstraintOptions constraints_;
  bool started_ = false;
  double start_overlap_ = 0.0;
};

// Screens one IMU sample for the buffer: false (and counted) for a non-finite
// sample; a gap to the previous sample longer than max_gap_ns (imu.max_gap, the
// one IMU-gap threshold, which the readers count against too) is counted.
bool AcceptImu(const ImuSample& imu, const std::deque<ImuSample>& buffer, TimeNs max_gap_ns,
               OdometryStats* stats);

// The warnings the counts call for: scans the queue skipped (out of order,
// stamped ahead, after the IMU's end) and a time-offset estimate that reached
// its bound (TimeOffsetWarnings).
std::vector<std::string> StatsWarnings(const OdometryStats& stats);

// Scans waiting for the IMU data that covers them: both backends hand a scan
// to the estimator only once an IMU sample at or after its end has arrived.
class ScanQueue {
 public:
  // Judges the scan's stamps (lidar/scan_order.h) against the scans received
  // before it and the IMU received so far: out of order (a stamp repeated or
  // going back behind the newest scan taken: skipped, scans_out_of_order), or
  // taken, dropping the newest scans taken before it when their stamps
  // jumped ahead (scans_stamp_ahead). A scan taken is queued unless no IMU
  // state covers it yet (not initialized, or it starts before the
  // estimator's current time: scans_before_imu). So the estimates come out
  // in increasing time.
  void Add(Scan scan, bool initialized, TimeNs state_time_ns, OdometryStats* stats);
  // The newest IMU sample received (accepted or used for initialization).
  void NoteImu(TimeNs t_ns) { imu_end_ns_ = std::max(imu_end_ns_, t_ns); }
  // At the end of input: drops (and counts in scans_after_imu) the queued
  // scans that end more than max_gap_ns after the newest IMU sample: the IMU
  // stopped before the LiDAR, and such a scan would be estimated without IMU.
  void DropPastImu(TimeNs max_gap_ns, OdometryStats* stats);
  // True when the oldest scan's end, moved by shift_ns (an estimated time
  // offset), is covered by the buffered IMU samples.
  bool FrontReady(const std::deque<ImuSample>& imu_buffer, TimeNs shift_ns = 0) const {
    return !scans_.empty() && !imu_buffer.empty() &&
           imu_buffer.back().t_ns >= scans_.front().t_end_ns + shift_ns;
  }
  bool empty() const { return scans_.empty(); }
  size_t size() const { return scans_.size(); }
  const Scan& front() const { return scans_.front(); }
  Scan PopFront();
  // The oldest scan moved by shift_ns (the estimated time offset) onto the
  // IMU clock; nothing (counted in scans_out_of_order) when it then ends at
  // or before state_time_ns (the estimator's time): a change of the estimate
  // since it was queued moved it behind a scan already estimated, and
  // estimating it would step the trajectory back in time.
  std::optional<Scan> PopFrontShifted(TimeNs shift_ns, TimeNs state_time_ns, OdometryStats* stats);
  // Drops (and counts in scans_before_imu) the queued scans that start before
  // state_time_ns, as Add would have (after the estimated shift changed).
  void DropStartingBefore(TimeNs state_time_ns, OdometryStats* stats);

 private:
  // Drops the scan ending at end_ns that the screen found stamped ahead.
  void DropAhead(TimeNs end_ns, OdometryStats* stats);

  std::deque<Scan> scans_;
  ScanStampScreen screen_;
  std::deque<TimeNs> before_imu_ends_ns_;  // the recent scans counted in scans_before_imu
  TimeNs imu_end_ns_ = ScanStampScreen::kNoImu;  // the lowest TimeNs
};

}  // namespace rvlio

#pragma once
// The odometry pipeline: AddImu / AddScan in, one ScanResult per scan out.
// Per scan it reads like the recipe of docs/design.md "Data flow: from a recording to the outputs":
//   Predict -> Downsample -> Deskew -> Associate -> RV -> Update -> Insert.
// It owns one estimator and the map; no I/O.
#include <array>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/imu/propagator.h"
#include "rvlio/lidar/options.h"
#include "rvlio/map/map_cloud.h"
#include "rvlio/math/extrinsic_excitation.h"
#include "rvlio/math/time_offset_excitation.h"
#include "rvlio/math/pose.h"
#include "rvlio/odometry/divergence.h"
#include "rvlio/odometry/options.h"
#include "rvlio/odometry/reference.h"  // Localization
#include "rvlio/degeneracy/degeneracy.h"
#include "rvlio/rv/rv.h"

namespace rvlio {

enum class ScanStatus {
  kUpdated = 0,      // the estimator used the scan
  kMapInit = 1,      // first scan: it started the map
  kPredictOnly = 2,  // too few constraints: IMU prediction kept, scan inserted
  kDiverged = 3,     // update diverged: reset to the last good state
};
const char* ScanStatusName(ScanStatus s);

struct ScanResult {
  TimeNs t_ns = 0;  // scan end time: the output stamp
  Pose3 T_world_imu;
  Eigen::Vector3d v_world_imu = Eigen::Vector3d::Zero();
  ScanStatus status = ScanStatus::kUpdated;
  int raw_points = 0;
  int downsampled_points = 0;
  int constraints = 0;
  int iterations = 0;
  RvReport rv;
  DegeneracyReport degeneracy;  // the same fields for every degeneracy.method
  double ms = 0.0;  // processing time of this scan: CPU time of the calling thread
  Eigen::Vector3d mean_acc_imu = Eigen::Vector3d::Zero();  // mean specific force over the scan, m/s^2
  Eigen::Vector3d mean_gyro_imu = Eigen::Vector3d::Zero();  // mean rotation rate over the scan, rad/s
  ScanHealth health;  // what the divergence monitor read, and what it flagged
  // The backend's LiDAR-IMU extrinsic after this scan; set only while it is
  // estimated online (ieskf/smoother.estimate_extrinsics), to follow its convergence.
  std::optional<Pose3> T_imu_lidar;
  // The LiDAR-IMU time offset after this scan (s, t_imu = t_lidar_stamp +
  // offset) and its 1-sigma; set only while it is estimated online
  // (lidar.estimate_time_offset).
  std::optional<double> time_offset_s;
  double time_offset_std_s = 0.0;
  // With a reference map (odometry/reference.h): share of the scan's points
  // with an accepted reference plane, and whether the scan was matched to
  // the reference (else to the working map: out of the reference).
  std::optional<double> map_overlap;
  bool localized = false;
  // The rest of the state at t_ns, for propagating the pose at IMU rate
  // between scans (imu/propagator.h, `rvlio live`): gyro and accelerometer
  // biases (IMU frame) and gravity (world frame).
  Eigen::Vector3d bg_imu = Eigen::Vector3d::Zero();  // rad/s
  Eigen::Vector3d ba_imu = Eigen::Vector3d::Zero();  // m/s^2
  Eigen::Vector3d g_world = Eigen::Vector3d(0.0, 0.0, -9.81);  // m/s^2
  // Covariance of the pose at t_ns: [p_world_imu (m^2), rotation about the
  // world axes (rad^2)] (the order of ROS' nav_msgs/Odometry). Set by the
  // IESKF (its posterior); the smoother has none.
  std::optional<Eigen::Matrix<double, 6, 6>> pose_covariance_world;
};

// The monitor's view of a scan result (odometry/divergence.h).
HealthSample HealthSampleOf(const ScanResult& r);

// The state at a scan result's stamp, to propagate the pose at IMU rate from
// (imu/propagator.h for `rvlio live`, imu/imu_rate_trajectory.h for
// trajectory_imu.tum).
ImuEstimate ImuEstimateOf(const ScanResult& r);

// Online extrinsic estimation (ieskf.estimate_extrinsics or
// smoother.estimate_extrinsics), reported in summary.json ("extrinsic").
struct ExtrinsicReport {
  bool enabled = false;             // the backend's option is on
  bool estimated = false;           // some axis was excited and took part in the estimate
  double excited_fraction = 0.0;    // of (scan, axis) pairs with the axis free
  std::array<bool, 6> axis_excited{};  // [rot x y z, pos x y z] at the end of the run
  Vector6d std_ratio = Vector6d::Ones();  // posterior / prior std per axis, all axes estimated
  Pose3 T_imu_lidar_prior;          // configured
  Pose3 T_imu_lidar;                // final estimate
  int64_t map_rebuilds = 0;         // working map re-anchored to a moved estimate (map.reanchor_*)
};

// The report of a backend's excitation monitor and its current estimate.
ExtrinsicReport MakeExtrinsicReport(const ExtrinsicExcitation& excitation,
                                    const Pose3& T_imu_lidar_prior, const Pose3& T_imu_lidar);

// Online time-offset estimation (lidar.estimate_time_offset), reported in
// summary.json ("time_offset"; math/time_offset_excitation.h). The note and
// the warning of the run are made from it (TimeOffsetNote,
// TimeOffsetWarnings): one source for what summary.json and stderr say.
struct TimeOffsetReport {
  bool enabled = false;
  double prior_s = 0.0;     // lidar.time_offset
  double estimate_s = 0.0;  // final estimate
  double std_s = 0.0;       // its 1-sigma
  bool at_bound = false;    // the final estimate is held at +-lidar.time_offset_max
  double bound_s = 0.0;     // lidar.time_offset_max
  int64_t bound_scans = 0;  // scans whose estimate was held at the bound
  TimeNs first_bound_t_ns = 0;  // the first of them (bound_scans > 0)
  bool excited = false;     // the motion excited it (TimeOffsetExcitation::excited)
  double excited_s = 0.0;   // seconds of excited scans
  double scans_s = 0.0;     // seconds from the first to the last scan counted
  double max_rate_spread_rad_s = 0.0;
  double max_velocity_spread_m_s = 0.0;
  double trust_std_s = 0.0;  // lidar.time_offset_excited_std
  // excited, 1-sigma under time_offset_excited_std, never at the bound
  bool trustworthy = false;
  int64_t map_hold_scans = 0;  // IESKF: lidar.time_offset_map_hold (0 for the smoother)
  int64_t replayed_scans = 0;  // IESKF: lidar.time_offset_replay (0 for the smoother)
};

// Brings the report of a backend's time-offset estimate up to the scan
// processed at t_ns: its estimate (estimate_s, std_s, at_bound: held at the
// bound) and excitation monitor, under the lidar options.
void UpdateTimeOffsetReport(const TimeOffsetExcitation& excitation, const LidarOptions& lidar,
                            double estimate_s, double std_s, bool at_bound, TimeNs t_ns,
                            TimeOffsetReport* r);
// What to do with the estimate, from what was measured (summary.json note).
std::string TimeOffsetNote(const TimeOffsetReport& r);
// The run's warning when the estimate reached the bound (else none).
std::vector<std::string> TimeOffsetWarnings(const TimeOffsetReport& r);

// Counts of what was skipped or repaired, reported in summary.json.
struct OdometryStats {
  int64_t scans_received = 0;
  int64_t scans_processed = 0;
  int64_t scans_before_imu = 0;       // LiDAR started before the IMU / during initialization
  int64_t scans_too_few_points = 0;   // skipped: fewer than kMinScanPoints after preprocessing
  int64_t predict_only = 0;
  int64_t diverged_resets = 0;
  int64_t imu_gaps_over_scan = 0;     // IMU gaps longer than imu.max_gap (the name is kept for summary.json)
  bool initialized = false;
  bool started_moving = false;        // static initialization saw motion
  // Sliding-window smoother (backend: smoother); zero for the IESKF.
  int64_t imu_factors_skipped = 0;       // window states added without an IMU factor (IMU gap)
  int64_t marginalization_failures = 0;  // replaced by a prior at the next state's estimate
  int64_t scans_out_of_order = 0;        // stamp repeating or going back, or moved behind the
                                         // estimator's time by a changed time-offset estimate: skipped
  int64_t scans_stamp_ahead = 0;         // stamp jumped ahead of the scans after it and the IMU: skipped
  int64_t scans_after_imu = 0;           // ending more than imu.max_gap after the last IMU sample
  int64_t imu_non_finite = 0;            // non-finite IMU samples dropped
  double association_ms = 0.0;           // CPU ms in association, RV and robust weights (total)
  double solve_ms = 0.0;                 // CPU ms in building and solving the window (total)
  double marginalization_ms = 0.0;       // CPU ms in marginalization (total)
  ExtrinsicReport extrinsic;
  TimeOffsetReport time_offset;
};

class Odometry {
 public:
  // Validates the options; fails for a backend this build does not have.
  // With localization.reference set, the odometry localizes in that map
  // from localization.T_ref_imu_initial (odometry/reference.h).
  static StatusOr<std::unique_ptr<Odometry>> Create(const OdometryOptions& options,
                                                    Localization localization = {});
  virtual ~Odometry() = default;

  virtual void AddImu(const ImuSample& imu) = 0;
  virtual void AddScan(Scan scan) = 0;
  // Processes every buffered scan whose end is covered by IMU data.
  virtual void Poll(std::vector<ScanResult>* out) = 0;
  // End of input: processes the remaining scans with the IMU data there is.
  virtual void Finish(std::vector<ScanResult>* out) = 0;

  virtual const OdometryStats& stats() const = 0;
  virtual std::vector<std::string> warnings() const = 0;
  // The divergence monitor's findings over the scans processed so far.
  virtual const DivergenceReport& divergence() const = 0;
  // The full map for output (coarse resolution), world frame.
  virtual std::vector<Eigen::Vector3d> MapPoints() const = 0;
  // The same points with their attributes (map/output_map.h): intensity and
  // ring as the recording gives them, each point's time (on the IMU clock, as
  // the results' stamps) and the index of its scan's result.
  virtual MapCloud MapWithAttributes() const = 0;
  // Not ok once the run cannot go on: with a reference map, the first scan
  // did not align to it (InvalidInput naming the cause). Poll/Finish then do nothing.
  virtual const Status& status() const = 0;
};

}  // namespace rvlio

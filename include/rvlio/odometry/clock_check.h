#pragma once
// Offline LiDAR-IMU clock check (`rvlio calibrate-time`, docs/time_offset.md).
//
// The rotation between consecutive scans, from registering each scan against
// the previous one with the odometry's own association and iterated
// point-to-plane update (an Ieskf with a loose prior and no IMU), gives the
// LiDAR's mean rotation rate over each interval between scan mid-times. The
// gyroscope's mean rate over the same interval shifted by a lag tau (plus a
// constant bias) is compared with it; the lag that minimizes the summed
// squared difference over the recording is the clock offset still missing
// from lidar.time_offset: t_imu = t_lidar + time_offset + tau. The search is
// coarse (a grid of kCoarseStepS over +-max_lag) then refined (golden
// section to kRefineToleranceS). Confidence: the 1-sigma of tau from the
// curvature of the cost (residual variance over the summed squared rate
// changes), and the fraction of the LiDAR rate variance the gyroscope
// explains at that lag.
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/time.h"
#include "rvlio/common/types.h"
#include "rvlio/constraints/options.h"
#include "rvlio/ieskf/ieskf.h"
#include "rvlio/lidar/preprocess.h"
#include "rvlio/map/options.h"
#include "rvlio/map/voxel_map.h"
#include "rvlio/math/pose.h"
#include "rvlio/odometry/options.h"

namespace rvlio {

// The LiDAR's mean rotation rate over [t0_ns, t1_ns] (IMU frame, rad/s).
struct LidarRateSample {
  TimeNs t0_ns = 0, t1_ns = 0;
  Eigen::Vector3d rate_imu = Eigen::Vector3d::Zero();
};

// Scan-to-scan registration: each scan (downsampled, not deskewed) against
// the previous one's points.
class ScanRotationTracker {
 public:
  explicit ScanRotationTracker(const OdometryOptions& options);
  // The rate between the previous scan's mid-time and this one's; nothing
  // for the first scan, a scan with too few points, or a failed registration.
  std::optional<LidarRateSample> Add(const Scan& scan);

 private:
  OdometryOptions options_;
  ScanPreprocessor preprocessor_;
  Ieskf solver_;
  Pose3 T_imu_lidar_;
  std::optional<VoxelMap> previous_;
  TimeNs previous_mid_ns_ = 0;
  Eigen::Matrix3d R_step_ = Eigen::Matrix3d::Identity();  // last relative rotation (LiDAR)
  Scan downsampled_;
  std::vector<Eigen::Vector3d> p_lidar_;
};

struct ClockCheckOptions {
  double max_lag_s = 0.2;              // search +-this around lidar.time_offset
  double min_rate_spread = 0.05;       // rad/s: less rotation-rate spread is "not enough rotation"
  double max_std_s = 0.002;            // s: a 1-sigma above this is "not enough rotation"
};

struct ClockCheckResult {
  int intervals = 0;               // LiDAR rate samples used
  bool enough_rotation = false;
  double lag_s = 0.0;              // add to lidar.time_offset
  double std_s = 0.0;              // 1-sigma of lag_s
  double explained = 0.0;          // fraction of the LiDAR rate variance explained at lag_s
  double rate_spread_rad_s = 0.0;  // rotation excitation: RMS spread of the gyro rate
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();  // rad/s, fitted with the lag
};

// The lag search over the LiDAR rates and the IMU samples (time order).
ClockCheckResult EstimateClockLag(const std::vector<LidarRateSample>& lidar,
                                  const std::vector<ImuSample>& imu,
                                  const ClockCheckOptions& options);

// What the stamps alone tell: scan period, jitter, drops; IMU rate stability.
struct StampReport {
  int scans = 0;
  double scan_period_s = 0.0;      // median
  double scan_jitter_s = 0.0;      // RMS deviation of the periods from the median (drops excluded)
  int dropped_scans = 0;           // periods of about k >= 2 medians count k - 1
  double scan_duration_s = 0.0;    // median t_end - t_start
  int imu_samples = 0;
  double imu_rate_hz = 0.0;        // 1 / median period
  double imu_jitter_s = 0.0;       // RMS deviation of the periods from the median
  int imu_gaps = 0;                // periods above twice the median
  double imu_max_gap_s = 0.0;
};

// scan_start_ns / scan_end_ns: per scan, in time order; imu_ns likewise.
StampReport AnalyzeStamps(const std::vector<TimeNs>& scan_start_ns,
                          const std::vector<TimeNs>& scan_end_ns,
                          const std::vector<TimeNs>& imu_ns);

}  // namespace rvlio

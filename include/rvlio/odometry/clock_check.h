#pragma once
// Offline LiDAR-IMU clock check (`rvlio calibrate-time`, docs/time_offset.md).
//
// The rotation between consecutive scans, from registering each scan
// (downsampled, not deskewed) against the previous one with the odometry's
// own association and iterated point-to-plane update (an Ieskf with a loose
// prior and no IMU), is compared with the gyroscope shifted by a lag tau
// (plus a constant bias). Without deskew each point sees the rotation
// between its own time and the time of the previous scan's points it is
// matched to, so a sample is a weighted sum of the gyro's rotation over
// those intervals (LidarRateSample), not the rotation between the scans'
// mid-times. The lag that minimizes the summed squared difference over the
// recording is the clock offset still missing from lidar.time_offset:
// t_imu = t_lidar + time_offset + tau. The search is coarse (a grid of
// kCoarseStepS over +-max_lag) then refined (golden section to
// kRefineToleranceS). Its 1-sigma is a sandwich (heteroscedasticity and
// autocorrelation consistent) estimate: the residuals are mostly
// registration errors, different per axis and correlated from scan to scan.
#include <optional>
#include <unordered_map>
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

// One share of a LiDAR rotation sample: the points of a scan taken around
// t1_ns, matched to points of the previous scan taken around t0_ns, see the
// sensor's rotation over [t0_ns, t1_ns]; `weight` (IMU frame) is their share
// of the registered rotation.
struct RotationSamplePart {
  TimeNs t0_ns = 0, t1_ns = 0;
  Eigen::Matrix3d weight = Eigen::Matrix3d::Identity();
};

// The LiDAR's rotation between two consecutive scans as a mean rate over the
// scan period (IMU frame, rad/s): to first order the sum over the parts of
// weight * (the mean rate over the part's interval). The weights come from
// the registration's information (the rotation rows of H^-1 H_part, H_part
// the point-to-plane information of the part's constraints; they sum to the
// identity less the prior's share, which is taken out of rate_imu). On a
// spinning LiDAR in a tunnel they are far from uniform over the sweep:
// taking the sample as the rate between the scans' mid-times biased the lag
// by that difference (-6 ms on an 8 s swaying flight, docs/time_offset.md).
struct LidarRateSample {
  Eigen::Vector3d rate_imu = Eigen::Vector3d::Zero();
  TimeNs period_ns = 0;  // between the two scans' starts
  std::vector<RotationSamplePart> parts;
};

// Scan-to-scan registration: each scan (downsampled, not deskewed) against
// the previous one's points.
class ScanRotationTracker {
 public:
  explicit ScanRotationTracker(const OdometryOptions& options);
  // The rotation since the previous scan; nothing for the first scan, a scan
  // with too few points, a scan not starting after the previous one, or a
  // failed registration.
  std::optional<LidarRateSample> Add(const Scan& scan);

 private:
  // The constraints at the registration's solution, each with the mean time
  // of the previous scan's points its plane was fitted to (-1: unknown).
  void AssociateAtSolution();
  // The sample of the registration just made from `prior`.
  std::optional<LidarRateSample> Sample(const FilterState& prior, TimeNs period_ns);
  void KeepAsPrevious(TimeNs t_start_ns);

  OdometryOptions options_;
  ScanPreprocessor preprocessor_;
  Ieskf solver_;
  Pose3 T_imu_lidar_;
  std::optional<VoxelMap> previous_;  // the previous scan's points (its LiDAR frame)
  std::unordered_map<uint64_t, TimeNs> previous_times_;  // their times, by PointKey
  TimeNs previous_start_ns_ = 0;
  Eigen::Matrix3d R_step_ = Eigen::Matrix3d::Identity();  // last relative rotation (LiDAR)
  Eigen::Vector3d t_step_ = Eigen::Vector3d::Zero();      // and translation
  Scan downsampled_;
  std::vector<Eigen::Vector3d> p_lidar_;
  ConstraintList constraints_;
  std::vector<TimeNs> map_time_ns_;  // per constraint
};

struct ClockCheckOptions {
  double max_lag_s = 0.2;         // search +-this around lidar.time_offset
  double min_rate_spread = 0.05;  // rad/s: less rotation-rate spread is "not enough rotation"
  double min_moving_s = 3.0;      // s of rotating intervals below which a recording is too short
  double max_std_s = 0.002;       // s: a 1-sigma above this cannot judge the offset
};

// What a recording lets the clock check say.
enum class ClockVerdict {
  kNoData,             // fewer than 3 usable intervals
  kNotEnoughRotation,  // the gyro rate hardly changes (rate spread below min_rate_spread)
  kTooShort,           // rotation, but over less than min_moving_s
  kTooUncertain,       // the 1-sigma is above max_std_s
  kJudged,             // lag_s, std_s stand
};

struct ClockCheckResult {
  ClockVerdict verdict = ClockVerdict::kNoData;
  int intervals = 0;               // LiDAR rate samples used
  double lag_s = 0.0;              // add to lidar.time_offset
  double std_s = 0.0;              // 1-sigma of lag_s
  double explained = 0.0;          // fraction of the LiDAR rate variance explained at lag_s
  double rate_spread_rad_s = 0.0;  // rotation excitation: RMS spread of the gyro rate
  double moving_s = 0.0;           // seconds of intervals whose rate is min_rate_spread off its mean
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

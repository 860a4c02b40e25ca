#include "rvlio/odometry/odometry.h"

#include "rvlio/odometry/ieskf_odometry.h"
#include "rvlio/odometry/smoother_odometry.h"

#include <cstdio>
#include <utility>

namespace rvlio {

const char* ScanStatusName(ScanStatus s) {
  switch (s) {
    case ScanStatus::kUpdated: return "updated";
    case ScanStatus::kMapInit: return "map_init";
    case ScanStatus::kPredictOnly: return "predict_only";
    case ScanStatus::kDiverged: return "diverged";
  }
  return "unknown";
}

HealthSample HealthSampleOf(const ScanResult& r) {
  HealthSample s;
  s.t_ns = r.t_ns;
  s.p_world_imu = r.T_world_imu.t;
  s.v_world_imu = r.v_world_imu;
  s.associated = r.status != ScanStatus::kMapInit;
  s.points = r.downsampled_points;
  s.constraints = r.constraints;
  if (r.mean_acc_imu.squaredNorm() > 0.0) s.specific_force_mps2 = r.mean_acc_imu.norm();
  s.mean_gyro_imu = r.mean_gyro_imu;
  s.health = r.health;
  return s;
}

ImuEstimate ImuEstimateOf(const ScanResult& r) {
  ImuEstimate e;
  e.state.t_ns = r.t_ns;
  e.state.R_world_imu = r.T_world_imu.R;
  e.state.p_world_imu = r.T_world_imu.t;
  e.state.v_world_imu = r.v_world_imu;
  e.bg_imu = r.bg_imu;
  e.ba_imu = r.ba_imu;
  e.g_world = r.g_world;
  return e;
}

ExtrinsicReport MakeExtrinsicReport(const ExtrinsicExcitation& excitation,
                                    const Pose3& T_imu_lidar_prior, const Pose3& T_imu_lidar) {
  ExtrinsicReport r;
  r.enabled = true;
  r.estimated = excitation.any_excited();
  r.excited_fraction = excitation.excited_fraction();
  for (int i = 0; i < 6; ++i) r.axis_excited[i] = excitation.excited(i);
  r.std_ratio = excitation.std_ratio();
  r.T_imu_lidar_prior = T_imu_lidar_prior;
  r.T_imu_lidar = T_imu_lidar;
  return r;
}

void UpdateTimeOffsetReport(const TimeOffsetExcitation& excitation, const LidarOptions& lidar,
                            double estimate_s, double std_s, bool at_bound, TimeNs t_ns,
                            TimeOffsetReport* r) {
  r->enabled = true;
  r->prior_s = lidar.time_offset;
  r->estimate_s = estimate_s;
  r->std_s = std_s;
  r->at_bound = at_bound;
  r->bound_s = lidar.time_offset_max;
  if (at_bound && r->bound_scans++ == 0) r->first_bound_t_ns = t_ns;
  r->excited = excitation.excited();
  r->excited_s = excitation.excited_seconds();
  r->scans_s = excitation.counted_seconds();
  r->max_rate_spread_rad_s = excitation.max_rate_spread();
  r->max_velocity_spread_m_s = excitation.max_velocity_spread();
  r->trust_std_s = lidar.time_offset_excited_std;
  r->trustworthy = r->excited && std_s < lidar.time_offset_excited_std && r->bound_scans == 0;
}

namespace {

// "held at the bound since t=..." or "reached the bound on N scans (first at
// t=...) and ended at X s".
std::string BoundText(const TimeOffsetReport& r) {
  char text[320];
  if (r.at_bound)
    std::snprintf(text, sizeof(text),
                  "the estimated LiDAR-IMU time offset is held at lidar.time_offset_max (%+g s) "
                  "at the end of the run (%lld scans at the bound, the first at t=%.3f s)",
                  r.estimate_s, static_cast<long long>(r.bound_scans),
                  NsToSeconds(r.first_bound_t_ns));
  else
    std::snprintf(text, sizeof(text),
                  "the estimated LiDAR-IMU time offset reached lidar.time_offset_max (%g s) on "
                  "%lld scans (the first at t=%.3f s) and ended at %.4f s",
                  r.bound_s, static_cast<long long>(r.bound_scans),
                  NsToSeconds(r.first_bound_t_ns), r.estimate_s);
  return text;
}

}  // namespace

std::string TimeOffsetNote(const TimeOffsetReport& r) {
  char measured[320];
  std::snprintf(measured, sizeof(measured),
                "%.1f s of the %.1f s of scans excited the offset (needed: %g s; rotation-rate "
                "spread up to %.2f rad/s, velocity spread up to %.2f m/s), 1-sigma %.3g ms",
                r.excited_s, r.scans_s, TimeOffsetExcitation::kMinExcitedSeconds,
                r.max_rate_spread_rad_s, r.max_velocity_spread_m_s, 1e3 * r.std_s);
  if (r.trustworthy) return std::string("put estimate_s in lidar.time_offset: ") + measured;
  if (r.bound_scans > 0)
    return "not trustworthy: " + BoundText(r) +
           "; keep lidar.time_offset and check the recording with `rvlio calibrate-time`";
  if (!r.excited) {
    const bool never_moved = r.max_rate_spread_rad_s < TimeOffsetExcitation::kMinRateSpread &&
                             r.max_velocity_spread_m_s < TimeOffsetExcitation::kMinVelocitySpread;
    if (never_moved) {
      std::snprintf(measured, sizeof(measured),
                    "not trustworthy: the motion never excited the time offset (rotation-rate "
                    "spread at most %.3f rad/s, needed %g; velocity spread at most %.3f m/s, "
                    "needed %g: a hover or a constant velocity); keep lidar.time_offset",
                    r.max_rate_spread_rad_s, TimeOffsetExcitation::kMinRateSpread,
                    r.max_velocity_spread_m_s, TimeOffsetExcitation::kMinVelocitySpread);
      return measured;
    }
    return std::string("not trustworthy yet: ") + measured +
           "; keep lidar.time_offset, or record longer with this motion to confirm it";
  }
  char std_text[160];
  std::snprintf(std_text, sizeof(std_text),
                " above lidar.time_offset_excited_std %g ms: the estimate is not settled",
                1e3 * r.trust_std_s);
  return std::string("not trustworthy: ") + measured + std_text;
}

std::vector<std::string> TimeOffsetWarnings(const TimeOffsetReport& r) {
  if (!r.enabled || r.bound_scans == 0) return {};
  return {BoundText(r) +
          ": the clocks differ by more, or the estimate is lost; check the recording with "
          "`rvlio calibrate-time` and set lidar.time_offset"};
}

StatusOr<std::unique_ptr<Odometry>> Odometry::Create(const OdometryOptions& options,
                                                     Localization localization) {
  OdometryOptions checked = options;
  if (Status s = checked.Validate(); !s.ok()) return s;
  switch (options.backend) {
    case Backend::kIeskf:
      return std::unique_ptr<Odometry>(new IeskfOdometry(options, std::move(localization)));
    case Backend::kSmoother:
      return std::unique_ptr<Odometry>(new SmootherOdometry(options, std::move(localization)));
  }
  return Status::InvalidInput("backend " + std::to_string(static_cast<int>(options.backend)) +
                              " is not a backend");
}

}  // namespace rvlio

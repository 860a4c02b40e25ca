#include "rvlio/odometry/odometry.h"

#include "rvlio/odometry/ieskf_odometry.h"
#include "rvlio/odometry/smoother_odometry.h"

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

TimeOffsetReport MakeTimeOffsetReport(const TimeOffsetExcitation& excitation,
                                      const LidarOptions& lidar, double estimate_s, double std_s,
                                      bool at_bound) {
  TimeOffsetReport r;
  r.enabled = true;
  r.prior_s = lidar.time_offset;
  r.estimate_s = estimate_s;
  r.std_s = std_s;
  r.at_bound = at_bound;
  r.bound_s = lidar.time_offset_max;
  r.excited = excitation.excited();
  r.excited_s = excitation.excited_seconds();
  r.max_rate_spread_rad_s = excitation.max_rate_spread();
  r.max_velocity_spread_m_s = excitation.max_velocity_spread();
  r.trustworthy = r.excited && std_s < lidar.time_offset_excited_std && !at_bound;
  return r;
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

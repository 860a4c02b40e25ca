#include "rvlio/outputs/extrinsic_json.h"

#include <cmath>
#include <vector>

#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

std::vector<double> ToList(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json PoseJson(const Pose3& T) {
  return {{"rpy_deg", ToList(RpyDeg(T.R))}, {"translation_m", ToList(T.t)}};
}

}  // namespace

nlohmann::json ExtrinsicJson(const ExtrinsicReport& r) {
  static const char* kAxes[6] = {"rot_x", "rot_y", "rot_z", "pos_x", "pos_y", "pos_z"};
  nlohmann::json excited = nlohmann::json::object(), ratio = nlohmann::json::object();
  for (int i = 0; i < 6; ++i) {
    excited[kAxes[i]] = r.axis_excited[i];
    ratio[kAxes[i]] = r.std_ratio(i);
  }
  const Eigen::Vector3d dphi = so3::Log(r.T_imu_lidar_prior.R.transpose() * r.T_imu_lidar.R);
  const Eigen::Vector3d dt = r.T_imu_lidar.t - r.T_imu_lidar_prior.t;
  return {{"estimated", r.estimated},
          {"excited_fraction", r.excited_fraction},
          {"axes_excited", excited},
          {"std_ratio_posterior_to_prior", ratio},
          {"T_imu_lidar", PoseJson(r.T_imu_lidar)},
          {"prior_T_imu_lidar", PoseJson(r.T_imu_lidar_prior)},
          {"map_rebuilds", r.map_rebuilds},
          {"change_from_prior",
           {{"rotation_deg", dphi.norm() * kRadToDeg},
            {"translation_m", dt.norm()},
            {"translation_delta_m", ToList(dt)}}}};
}

nlohmann::json TimeOffsetJson(const TimeOffsetReport& r) {
  return {{"estimate_s", r.estimate_s},
          {"std_s", r.std_s},
          {"prior_s", r.prior_s},
          {"at_bound", r.at_bound},
          {"bound_s", r.bound_s},
          {"bound_scans", r.bound_scans},
          {"first_bound_time_s",
           r.bound_scans > 0 ? nlohmann::json(NsToSeconds(r.first_bound_t_ns)) : nlohmann::json()},
          {"excited", r.excited},
          {"excited_s", r.excited_s},
          {"scans_s", r.scans_s},
          {"max_rotation_rate_spread_rad_s", r.max_rate_spread_rad_s},
          {"max_velocity_spread_m_s", r.max_velocity_spread_m_s},
          {"trustworthy", r.trustworthy},
          {"map_hold_scans", r.map_hold_scans},
          {"replayed_scans", r.replayed_scans},
          {"note", TimeOffsetNote(r)}};
}

}  // namespace rvlio

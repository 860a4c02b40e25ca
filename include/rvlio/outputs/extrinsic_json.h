#pragma once
// summary.json "extrinsic" and "time_offset": the online extrinsic and time
// offset estimates of a run (odometry.h ExtrinsicReport, TimeOffsetReport).
#include <nlohmann/json.hpp>

#include "rvlio/math/so3.h"  // RpyDeg
#include "rvlio/odometry/odometry.h"

namespace rvlio {

// {estimated, excited_fraction, axes_excited, std_ratio, T_imu_lidar, prior, change}.
nlohmann::json ExtrinsicJson(const ExtrinsicReport& r);

// summary.json "time_offset": {estimate_s, std_s, prior_s, at_bound, bound_s,
// excited, excited_s, max_*_spread, trustworthy, note}.
nlohmann::json TimeOffsetJson(const TimeOffsetReport& r);

}  // namespace rvlio

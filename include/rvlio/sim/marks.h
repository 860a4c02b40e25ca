#pragma once
// The survey frame of a simulation, its stop-and-go marks and GNSS fixes
// (options `marks` and `gnss`, docs/simulator.md "Survey frame, marks, GNSS").
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/types.h"
#include "rvlio/math/pose.h"
#include "rvlio/sim/simulator.h"

namespace rvlio::sim {

// T_survey_world: p_survey = Rz(yaw) p_world + (E, N, h).
Pose3 SurveyFromWorld(const SimMarksOptions& marks);

struct SimMark {
  std::string name;                 // M1, M2, ... in time order
  bool check = false;
  Eigen::Vector3d p_survey_true = Eigen::Vector3d::Zero();  // the floor under the IMU
  Eigen::Vector3d p_survey = Eigen::Vector3d::Zero();       // with marks.noise_m
  TimeNs t_start_ns = 0, t_end_ns = 0;  // the rest on it (within the simulated span)
};
// The floor point under the IMU at every rest on the floor (the static phase
// and each landing) that lasts at least 1 s within the simulated span. The
// IMU stands world.start_height above it, so the lever arm (IMU origin from
// the mark, body frame at rest) is (0, 0, world.start_height).
std::vector<SimMark> SimulateMarks(const Simulator& simulator);

struct SimFix {
  TimeNs t_ns = 0;
  Eigen::Vector3d p_survey = Eigen::Vector3d::Zero();  // the antenna, with noise
  bool outlier = false;
};
// Fixes every 1/gnss.rate s while the antenna is outside the tunnel by
// gnss.portal_margin_m (before the entrance, or past an open far end).
std::vector<SimFix> SimulateFixes(const Simulator& simulator);

}  // namespace rvlio::sim

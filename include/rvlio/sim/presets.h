#pragma once
// Named simulator configurations:
//   tunnel      the paper's Gazebo tunnel: 10.45 x 7.8 x 100.5 m, OS1-32,
//               waypoints [0,0,0] -> [0,0,2.5] -> [30,0,2.5] -> [30,0,4.5] -> [50,0,4.5]
//   corridor    narrow and long like the paper's real tunnel (5.8 x 5.0 x 225.5 m), OS0-32 (+-45
//   deg) loopback    the corridor, flown in and back out to the start pose hall        a
//   feature-rich room with pillars, boxes, stairs and doorways (nothing degenerate) featureless a
//   long smooth tunnel without any feature and with both ends
//               beyond the LiDAR range: the axial position is unobservable (paper Remark 3)
//   stopgo      stop-and-go over 200 m of the tunnel: landings on floor marks every 50 m,
//               NAME_control.csv in a UTM-sized survey frame (docs/control.md)
//   portals     a 60 m tunnel open at both ends, flown from outside one portal to beyond the
//               other: GNSS fixes outside (docs/control.md "GNSS")
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/sim/options.h"

namespace rvlio::sim {

std::vector<std::string> PresetNames();
// InvalidInput listing the presets for an unknown name.
StatusOr<SimOptions> PresetOptions(const std::string& name);
// trajectory.waypoints of a stop-and-go flight along x: from the start (a
// mark), `legs` times up to height_m, spacing_m along, and down onto the
// next mark (z = 0: a landing with trajectory.landing_time).
std::string StopGoWaypoints(double spacing_m, int legs, double height_m);

}  // namespace rvlio::sim

#pragma once
// Named simulator configurations:
//   tunnel      the paper's Gazebo tunnel: 10.45 x 7.8 x 100.5 m, OS1-32,
//               waypoints [0,0,0] -> [0,0,2.5] -> [30,0,2.5] -> [30,0,4.5] -> [50,0,4.5]
//   corridor    narrow and long like the paper's real tunnel (5.8 x 5.0 x 225.5 m), OS0-32 (+-45
//   deg) loopback    the corridor, flown in and back out to the start pose hall        a
//   feature-rich room with pillars, boxes, stairs and doorways (nothing degenerate) featureless a
//   long smooth tunnel without any feature and with both ends
//               beyond the LiDAR range: the axial position is unobservable (paper Remark 3)
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/sim/options.h"

namespace rvlio::sim {

std::vector<std::string> PresetNames();
// InvalidInput listing the presets for an unknown name.
StatusOr<SimOptions> PresetOptions(const std::string& name);

}  // namespace rvlio::sim

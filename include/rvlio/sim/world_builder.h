#pragma once
// Builds the simulated world from SimOptions: the tunnel (or hall)
// shell with rough surfaces placed relative to the start pose, the
// feature-rich entrance region, sparse features, and for the hall pillars,
// stairs and doorways. Every random choice comes from the seed; features keep
// world.path_clearance from the flight path.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rvlio/sim/options.h"
#include "rvlio/sim/world.h"

namespace rvlio::sim {

// Where the shell lies in the world frame (m).
struct WorldLayout {
  double x_entrance = 0.0;  // entrance (tunnel) or front wall (hall)
  double x_end = 0.0;       // far end
  double y_center = 0.0;
  double half_width = 0.0;
  double z_floor = 0.0;
  double z_ceiling = 0.0;
  double clutter_end = 0.0;  // x where the feature-rich region ends
  bool Inside(const Eigen::Vector3d& p, double margin) const;
};

WorldLayout MakeLayout(const SimWorldOptions& options);

// path: points along the flight path (FlightTrajectory::SamplePath).
World BuildWorld(const SimWorldOptions& options, const std::vector<Eigen::Vector3d>& path,
                 uint64_t seed);

}  // namespace rvlio::sim

#pragma once
// `refine`'s result through the divergence monitor of the online odometry
// (odometry/divergence.h): refine uses the monitor; the odometry knows
// nothing of refine.
#include "rvlio/odometry/divergence.h"
#include "rvlio/refine/refine.h"

namespace rvlio {

// `refine`'s result through the same checks, scan by scan in time order:
// speed and jump from the refined poses and velocities, and the inlier
// fraction of the last round (constraints / points over all scans; refine
// keeps no per-scan figure). NIS and residuals are the IESKF's and the
// smoother's online figures and are not checked here.
DivergenceReport CheckRefineResult(const RefineResult& result, const DivergenceOptions& options,
                                   double lidar_noise_m, double gravity_mps2);

}  // namespace rvlio

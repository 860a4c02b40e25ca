#pragma once
// A static terrestrial laser-scanner survey of the simulated world: the
// reference map of `rvlio simulate --reference-map` (docs/simulator.md).
//
// Stations stand on the tunnel's centre line (y = layout.y_center) at
// survey.station_height above the floor, evenly along world x over the part
// of [x_entrance, x_end] inside [survey.x_min, survey.x_max], at most
// survey.station_spacing apart. A station that would stand in or within
// kStationClearance of a feature is raised in 0.5 m steps (a surveyor moves
// the tripod); where no height is free it is left out (stations_skipped).
// Each station casts rays over the full sphere with the world's own ray
// caster (World::Raycast): rings of constant elevation angular_step apart,
// each ring with round(2 pi cos(elevation) / angular_step) rays, so the rays
// are about angular_step apart everywhere; each station's rings start at a
// random azimuth (its own heading). Returns within [min_range, max_range]
// get Gaussian range noise; points outside [x_min, x_max] are dropped. The
// union over the stations is thinned to one point per voxel of edge
// voxel_size: the real return nearest the voxel centre (ScanPreprocessor's
// grid, lidar/preprocess.h), so every map point is a measured point.
//
// Deterministic: the station headings and noise come from the world seed
// (one stream per station), independent of the thread count.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/sim/options.h"
#include "rvlio/sim/world.h"
#include "rvlio/sim/world_builder.h"

namespace rvlio::sim {

constexpr double kStationClearance = 0.3;  // m, free space around a station

struct SurveyResult {
  std::vector<Eigen::Vector3d> p_world;   // the thinned map (world frame, m)
  std::vector<Eigen::Vector3d> stations;  // scanner positions used (world frame, m)
  int stations_skipped = 0;               // no free height at that x
  int64_t rays = 0;                       // cast
  int64_t returns = 0;                    // in range and inside the crop, before thinning
};

// InvalidInput naming survey.x_min / survey.x_max when the crop does not
// overlap the world's x extent, or when no station is free.
StatusOr<SurveyResult> SurveyWorld(const World& world, const WorldLayout& layout,
                                   const SimSurveyOptions& options, uint64_t seed);

}  // namespace rvlio::sim

#pragma once
// The deviation of an output map from the reference (`run --map`,
// `refine --map`, `merge --map`; docs/survey.md): map.pcd with a per-point
// deviation_m, deviation.csv per chainage bin, and the summary's figures.
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/outputs/map_las.h"
#include "rvlio/outputs/output_stage.h"
#include "rvlio/map/reference_map.h"
#include "rvlio/odometry/deviation.h"

namespace rvlio {

struct MapDeviation {
  PointDeviations points;          // per point of the output map
  std::vector<DeviationBin> bins;  // by chainage along the trajectory
};

// Each point of the output map p_map (reference frame, m) against the
// reference surface; the trajectory (sorted by time, non-empty) gives the
// view points and the chainage.
MapDeviation ComputeMapDeviation(const std::vector<Eigen::Vector3d>& p_map,
                                 const ReferenceMap& reference,
                                 const Trajectory& trajectory, const DeviationOptions& options);

// summary.json's localization.deviation: point counts and the median, 95th
// percentile and maximum absolute deviation (null without any surface).
nlohmann::json DeviationSummaryJson(const MapDeviation& d);

// map.pcd of the map (its points and attributes) into the stage, with the
// deviation_m field and deviation.csv beside it when `deviation` (of the
// map's points) is not null, and map.las of the same points and fields when
// las.enabled (output.las). The error is the stage's explanation (nothing of
// the stage is committed).
Status WriteMapOutputs(OutputStage* stage, const MapCloud& map, const MapDeviation* deviation,
                       const MapLasRequest& las = {});

}  // namespace rvlio

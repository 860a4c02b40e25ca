#include "rvlio/outputs/deviation_outputs.h"

#include <algorithm>
#include <cmath>

#include "rvlio/outputs/run_outputs.h"

namespace rvlio {

MapDeviation ComputeMapDeviation(const std::vector<Eigen::Vector3d>& p_map,
                                 const ReferenceMap& reference,
                                 const Trajectory& trajectory, const DeviationOptions& options) {
  MapDeviation d;
  d.points = ComputeDeviations(p_map, reference, trajectory, options.surface);
  d.bins = BinByChainage(d.points, options.chainage_step);
  return d;
}

nlohmann::json DeviationSummaryJson(const MapDeviation& d) {
  std::vector<double> abs_m;
  for (double v : d.points.deviation_m)
    if (std::isfinite(v)) abs_m.push_back(std::abs(v));
  std::sort(abs_m.begin(), abs_m.end());
  const auto at = [&abs_m](double q) {
    return abs_m.empty() ? nlohmann::json(nullptr)
                         : nlohmann::json(abs_m[std::min(abs_m.size() - 1,
                                                         static_cast<size_t>(q * abs_m.size()))]);
  };
  return {{"map_points", d.points.deviation_m.size()},
          {"with_surface", abs_m.size()},
          {"median_abs_m", at(0.5)},
          {"p95_abs_m", at(0.95)},
          {"max_abs_m", abs_m.empty() ? nlohmann::json(nullptr) : nlohmann::json(abs_m.back())}};
}

Status WriteMapOutputs(OutputStage* stage, const MapCloud& map, const MapDeviation* deviation,
                       const MapLasRequest& las) {
  const std::vector<double>* deviation_m =
      deviation != nullptr ? &deviation->points.deviation_m : nullptr;
  if (Status s = WriteMapPcd(stage->Path("map.pcd"), map, deviation_m); !s.ok())
    return stage->Explain(s);
  if (las.enabled)
    if (Status s = WriteMapLas(stage->Path("map.las"), map, deviation_m, las.crs_wkt); !s.ok())
      return stage->Explain(s);
  if (deviation != nullptr)
    if (Status s = WriteDeviationCsv(stage->Path("deviation.csv"), deviation->bins); !s.ok())
      return stage->Explain(s);
  return Status::Ok();
}

}  // namespace rvlio

#pragma once
// Deviation of a run's map from the reference map (`rvlio run --map`,
// docs/survey.md): per output-map point, the signed distance to the
// reference's local plane (QueryReferenceSurface, constraints/
// reference_surface.h), seen from the nearest trajectory position, so that
// a positive value lies on the open side of the reference surface (a
// convergence of a wall, a deposit) and a negative one behind it; NaN where
// the reference has no surface within the query radius. Then, along the
// trajectory, statistics per chainage bin (the along-track distance of the
// nearest trajectory position).
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/options.h"
#include "rvlio/common/types.h"
#include "rvlio/constraints/reference_surface.h"
#include "rvlio/map/reference_map.h"

namespace rvlio {

struct DeviationOptions {
  SurfaceQueryOptions surface;  // the reference plane of each map point
  double chainage_step = 1.0;   // m, bin length of deviation.csv

  template <class V>
  void Visit(V& v) {
    v.Field("chainage_step", chainage_step, Spec().Unit("m").Range(0.01, 1000.0)
        .Help("bin length along the trajectory of deviation.csv"));
    v.Section("surface", surface);
  }
};

// Which surface of a tunnel a map point lies on, seen from its nearest
// trajectory position: the reference plane's normal at the point faces
// mostly "up" across the track (the frame's +z with its along-track part
// removed: a floor or a ceiling, told apart by whether the point lies below
// or above the trajectory) or mostly "left" (up x forward: a wall, left or
// right by the side of the track it lies on). kNone: no reference surface,
// no trajectory position near, or a vertical stretch of trajectory (no
// across-track up).
enum class TunnelSide : uint8_t { kLeft = 0, kRight = 1, kFloor = 2, kCeiling = 3, kNone = 4 };
constexpr int kTunnelSides = 4;
const char* TunnelSideName(TunnelSide side);  // "left", "right", "floor", "ceiling", "none"

struct PointDeviations {
  std::vector<double> deviation_m;  // per map point, NaN without a reference surface
  std::vector<double> chainage_m;   // per map point, of its nearest trajectory position
  std::vector<TunnelSide> side;     // per map point
};

// Every map point against the reference; `trajectory` (sorted by time,
// non-empty) gives the view points and the chainage.
PointDeviations ComputeDeviations(const std::vector<Eigen::Vector3d>& p_map,
                                  const ReferenceMap& reference, const Trajectory& trajectory,
                                  const SurfaceQueryOptions& options);

struct DeviationBin {
  double chainage_m = 0.0;  // bin start
  int count = 0;            // points with a deviation
  double median_m = 0.0;    // signed
  double median_abs_m = 0.0;
  double p95_abs_m = 0.0;
  double max_abs_m = 0.0;
  // The same per surface (index: TunnelSide), so that one wall's movement is
  // not diluted by the other three: count, signed median, p95 |deviation|
  // (NaN without points).
  struct Side {
    int count = 0;
    double median_m = 0.0;
    double p95_abs_m = 0.0;
  };
  Side sides[kTunnelSides];
};

// Bins of step_m from chainage 0 to the last point's; empty bins have count 0
// and NaN statistics.
std::vector<DeviationBin> BinByChainage(const PointDeviations& d, double step_m);

}  // namespace rvlio

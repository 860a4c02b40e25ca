#include "rvlio/sim/survey.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "rvlio/common/parallel.h"
#include "rvlio/common/text.h"
#include "rvlio/common/types.h"
#include "rvlio/lidar/preprocess.h"
#include "rvlio/sim/random.h"

namespace rvlio::sim {

namespace {

constexpr double kDegToRad = M_PI / 180.0;
constexpr double kRaiseStep = 0.5;            // m, a station in a feature is raised by this
constexpr uint64_t kStationStreamBase = 5000;  // station k draws from stream base + k
constexpr int kStationsPerBatch = 4;           // per thread and batch (bounds the memory)

// The voxel grid of the map: ScanPreprocessor's (nearest to the voxel centre
// wins, ties keep the earlier point), on world coordinates, without a range
// crop or stride.
LidarOptions ThinningOptions(double voxel_size) {
  LidarOptions o;
  o.min_range = 0.0;
  o.max_range = 1.0e6;
  o.point_stride = 1;
  o.voxel_size = voxel_size;
  return o;
}

// Scanner position at world x, or false where no height is free.
bool PlaceStation(const World& world, const WorldLayout& layout, const SimSurveyOptions& o,
                  double x, Eigen::Vector3d* p_world) {
  for (double h = o.station_height; layout.z_floor + h <= layout.z_ceiling - kStationClearance;
       h += kRaiseStep) {
    const Eigen::Vector3d p(x, layout.y_center, layout.z_floor + h);
    if (!world.InsideFeature(p) && world.DistanceToSurface(p) >= kStationClearance) {
      *p_world = p;
      return true;
    }
  }
  return false;
}

// One station's returns inside the crop (world coordinates as LiDAR points),
// and the number of rays cast.
int64_t ScanStation(const World& world, const SimSurveyOptions& o, const Eigen::Vector3d& p_station,
                    uint64_t seed, int station, Scan* out) {
  out->points.clear();
  Rng rng = Rng::Stream(seed, kStationStreamBase + static_cast<uint64_t>(station));
  const double step = o.angular_step * kDegToRad;
  const double heading = rng.Uniform(0.0, 2.0 * M_PI);
  const int rings = std::max(1, static_cast<int>(std::lround(M_PI / step)));
  int64_t rays = 0;
  for (int i = 0; i < rings; ++i) {
    const double el = -0.5 * M_PI + (i + 0.5) * M_PI / rings;
    const double cos_el = std::cos(el), sin_el = std::sin(el);
    const int n = std::max(1, static_cast<int>(std::lround(2.0 * M_PI * cos_el / step)));
    const double shift = (i % 2 == 0) ? 0.0 : 0.5;  // stagger neighbouring rings
    for (int j = 0; j < n; ++j, ++rays) {
      const double az = heading + 2.0 * M_PI * (j + shift) / n;
      const Eigen::Vector3d dir(cos_el * std::cos(az), cos_el * std::sin(az), sin_el);
      RayHit hit;
      if (!world.Raycast(p_station, dir, o.max_range, &hit) || hit.range < o.min_range) continue;
      const double range = hit.range + (o.range_noise > 0.0 ? rng.Normal(o.range_noise) : 0.0);
      const Eigen::Vector3d p = p_station + range * dir;
      if (p.x() < o.x_min || p.x() > o.x_max) continue;
      LidarPoint pt;
      pt.p_lidar = p.cast<float>();
      out->points.push_back(pt);
    }
  }
  return rays;
}

}  // namespace

StatusOr<SurveyResult> SurveyWorld(const World& world, const WorldLayout& layout,
                                   const SimSurveyOptions& o, uint64_t seed) {
  const double lo = std::max(o.x_min, layout.x_entrance), hi = std::min(o.x_max, layout.x_end);
  if (!(lo <= hi))
    return Status::InvalidInput("survey.x_min/survey.x_max: [" + FormatG(o.x_min) + ", " +
                                FormatG(o.x_max) + "] m does not overlap the world's x extent [" +
                                FormatG(layout.x_entrance) + ", " + FormatG(layout.x_end) + "] m");
  SurveyResult r;
  const int count = std::max(1, static_cast<int>(std::ceil((hi - lo) / o.station_spacing)));
  for (int k = 0; k < count; ++k) {
    Eigen::Vector3d p;
    if (PlaceStation(world, layout, o, lo + (k + 0.5) * (hi - lo) / count, &p))
      r.stations.push_back(p);
    else
      ++r.stations_skipped;
  }
  if (r.stations.empty())
    return Status::InvalidInput(
        "survey: no free station position (features fill the centre line at every height)");

  const int stations = static_cast<int>(r.stations.size());
  const int threads = ResolveThreads(0);
  const int slots = ParallelSlots(threads, stations);
  std::vector<ScanPreprocessor> grids(static_cast<size_t>(slots),
                                      ScanPreprocessor(ThinningOptions(o.voxel_size)));
  std::vector<Scan> raw(static_cast<size_t>(slots));
  ScanPreprocessor merge_grid(ThinningOptions(o.voxel_size));
  Scan all, thinned;
  size_t last_thinned = 0;
  const int batch = kStationsPerBatch * slots;
  for (int first = 0; first < stations; first += batch) {
    const int last = std::min(stations, first + batch);
    std::vector<Scan> kept(static_cast<size_t>(last - first));
    std::vector<int64_t> rays(kept.size(), 0), returns(kept.size(), 0);
    ParallelFor(first, last, threads, [&](int k, int slot) {
      Scan& scan = raw[static_cast<size_t>(slot)];
      rays[static_cast<size_t>(k - first)] =
          ScanStation(world, o, r.stations[static_cast<size_t>(k)], seed, k, &scan);
      returns[static_cast<size_t>(k - first)] = static_cast<int64_t>(scan.points.size());
      grids[static_cast<size_t>(slot)].Downsample(scan, &kept[static_cast<size_t>(k - first)]);
    });
    for (size_t i = 0; i < kept.size(); ++i) {
      r.rays += rays[i];
      r.returns += returns[i];
      all.points.insert(all.points.end(), kept[i].points.begin(), kept[i].points.end());
    }
    // The nearest point to a voxel centre over the union is the nearest of
    // the per-station winners: thinning the union again whenever it has
    // doubled gives the same map as thinning everything at once.
    if (all.points.size() > 2 * last_thinned || last == stations) {
      merge_grid.Downsample(all, &thinned);
      std::swap(all, thinned);
      last_thinned = all.points.size();
    }
  }
  r.p_world.reserve(all.points.size());
  for (const LidarPoint& pt : all.points) r.p_world.push_back(pt.p_lidar.cast<double>());
  return r;
}

}  // namespace rvlio::sim

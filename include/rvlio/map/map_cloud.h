#pragma once
// An output map's points with the attributes of the LiDAR return each one
// is (map.pcd and map.las, docs/outputs.md "map.pcd"): what the output map
// (map/output_map.h) gives, what run, refine and merge write and read back.
// An attribute the map does not have (e.g. no intensity in the recording) is
// absent, not zero: its flag is false and its column empty; a present one
// has one value per point.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/time.h"

namespace rvlio {

struct MapCloud {
  std::vector<Eigen::Vector3d> p;  // m, the map's frame
  std::vector<float> intensity;    // the sensor's unit (its reflectivity where it gives one)
  std::vector<TimeNs> t_ns;        // acquisition time, absolute (the trajectory's clock)
  std::vector<uint16_t> ring;      // beam
  std::vector<uint32_t> scan_index;  // the scan's row in trajectory.tum
  bool has_intensity = false, has_time = false, has_ring = false, has_scan_index = false;

  size_t size() const { return p.size(); }
  // Every column has one value per point exactly when its flag is set.
  bool Consistent() const;
};

bool operator==(const MapCloud& a, const MapCloud& b);
inline bool operator!=(const MapCloud& a, const MapCloud& b) { return !(a == b); }

}  // namespace rvlio

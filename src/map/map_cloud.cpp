#include "rvlio/map/map_cloud.h"

namespace rvlio {
namespace {

template <typename T>
bool Sized(const std::vector<T>& column, bool present, size_t n) {
  return column.size() == (present ? n : 0);
}

}  // namespace

bool MapCloud::Consistent() const {
  const size_t n = p.size();
  return Sized(intensity, has_intensity, n) && Sized(t_ns, has_time, n) &&
         Sized(ring, has_ring, n) && Sized(scan_index, has_scan_index, n);
}

bool operator==(const MapCloud& a, const MapCloud& b) {
  return a.p == b.p && a.intensity == b.intensity && a.t_ns == b.t_ns && a.ring == b.ring &&
         a.scan_index == b.scan_index && a.has_intensity == b.has_intensity &&
         a.has_time == b.has_time && a.has_ring == b.has_ring &&
         a.has_scan_index == b.has_scan_index;
}

}  // namespace rvlio

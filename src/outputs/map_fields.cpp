#include "rvlio/outputs/map_fields.h"

#include <cmath>

namespace rvlio {
namespace {

constexpr MapFieldSpec kSpecs[] = {
    {MapField::kIntensity, "intensity", 'F', 4},
    {MapField::kTime, "time", 'F', 8},
    {MapField::kRing, "ring", 'U', 2},
    {MapField::kScanIndex, "scan_index", 'U', 4},
    {MapField::kDeviation, "deviation_m", 'F', 4},
};

bool MapHasField(const MapCloud& map, MapField f, bool with_deviation) {
  switch (f) {
    case MapField::kIntensity: return map.has_intensity;
    case MapField::kTime: return map.has_time;
    case MapField::kRing: return map.has_ring;
    case MapField::kScanIndex: return map.has_scan_index;
    case MapField::kDeviation: return with_deviation;
  }
  return false;
}

}  // namespace

double MapTimeSeconds(TimeNs t_ns) {
  TimeNs whole_s = t_ns / kNsPerSecond, fraction_ns = t_ns % kNsPerSecond;
  if (fraction_ns < 0) --whole_s, fraction_ns += kNsPerSecond;
  return static_cast<double>(whole_s) + static_cast<double>(fraction_ns) * 1e-9;
}

TimeNs MapTimeNs(double t_s) {
  const double whole_s = std::floor(t_s);
  return static_cast<TimeNs>(whole_s) * kNsPerSecond +
         static_cast<TimeNs>(std::llround((t_s - whole_s) * 1e9));
}

std::vector<MapFieldSpec> MapAttributeFields(const MapCloud& map, bool with_deviation) {
  std::vector<MapFieldSpec> out;
  for (const MapFieldSpec& s : kSpecs)
    if (MapHasField(map, s.field, with_deviation)) out.push_back(s);
  return out;
}

const MapFieldSpec* MapFieldByName(const std::string& name) {
  for (const MapFieldSpec& s : kSpecs)
    if (name == s.name) return &s;
  return nullptr;
}

double MapFieldValue(MapField f, const MapCloud& map, const std::vector<double>* deviation_m,
                     size_t i) {
  switch (f) {
    case MapField::kIntensity: return map.intensity[i];
    case MapField::kTime: return MapTimeSeconds(map.t_ns[i]);
    case MapField::kRing: return map.ring[i];
    case MapField::kScanIndex: return map.scan_index[i];
    case MapField::kDeviation: return (*deviation_m)[i];
  }
  return 0.0;
}

}  // namespace rvlio

#pragma once
// The per-point fields of map.pcd after x y z, in file order (docs/outputs.md
// "map.pcd"): the map's attributes (map/map_cloud.h) and deviation_m. One
// list for the PCD writer, the PCD reader (ReadMapCloud) and map.las, so the
// three agree on names, types and order.
#include <cstddef>
#include <string>
#include <vector>

#include "rvlio/map/map_cloud.h"

namespace rvlio {

enum class MapField { kIntensity, kTime, kRing, kScanIndex, kDeviation };

struct MapFieldSpec {
  MapField field;
  const char* name;  // the PCD field
  char type;         // PCD TYPE: F, U
  int size;          // bytes
};

// intensity F4, time F8 (UNIX seconds), ring U2, scan_index U4: those the
// map has; then deviation_m F4 when with_deviation.
std::vector<MapFieldSpec> MapAttributeFields(const MapCloud& map, bool with_deviation);

// The spec of a field by its PCD name, or nullptr for a name that is not a
// map attribute.
const MapFieldSpec* MapFieldByName(const std::string& name);

// A map time as UNIX seconds in a double and back, the whole seconds apart
// from the fraction: a round trip keeps the time to 0.12 us (half the
// double's step at today's times), where t * 1e-9 loses up to 0.37 us.
double MapTimeSeconds(TimeNs t_ns);
TimeNs MapTimeNs(double t_s);  // t_s finite

// Field f of point i as a double (time: MapTimeSeconds); deviation_m may be
// null when f is not kDeviation.
double MapFieldValue(MapField f, const MapCloud& map, const std::vector<double>* deviation_m,
                     size_t i);

}  // namespace rvlio

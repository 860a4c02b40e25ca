#pragma once
// Time at every interface is int64 nanoseconds; double seconds only inside a
// computation (docs/design.md "Conventions").
#include <cstdint>

namespace rvlio {

using TimeNs = int64_t;

constexpr TimeNs kNsPerSecond = 1000000000LL;

inline double NsToSeconds(TimeNs t_ns) { return static_cast<double>(t_ns) * 1e-9; }
inline TimeNs SecondsToNs(double t_s) {
  return static_cast<TimeNs>(t_s * 1e9 + (t_s >= 0 ? 0.5 : -0.5));
}

}  // namespace rvlio

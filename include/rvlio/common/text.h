#pragma once
// Numbers and lists as text: the one home of the project's small formatters
// (printf's %g and %f) and of joining names into one line.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace rvlio {

// v with `significant` significant digits, shortest form (printf "%.*g", as
// an ostream with that precision prints it): FormatG(0.1) "0.1", FormatG(2e-05) "2e-05".
inline std::string FormatG(double v, int significant = 6) {
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%.*g", significant, v);
  return buf;
}

// FormatG, or "" for a value that is not finite (unknown: an empty CSV field).
inline std::string FormatFinite(double v, int significant) {
  return std::isfinite(v) ? FormatG(v, significant) : std::string();
}

// v with `decimals` digits after the point (printf "%.*f").
inline std::string FormatFixed(double v, int decimals) {
  char buf[352];  // %f of the largest double has 309 digits before the point
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
  return buf;
}

// The items with `separator` between them ("" for none).
inline std::string Join(const std::vector<std::string>& items, const std::string& separator) {
  std::string text;
  for (size_t i = 0; i < items.size(); ++i) text += (i == 0 ? "" : separator) + items[i];
  return text;
}

}  // namespace rvlio

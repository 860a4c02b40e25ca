#pragma once
// Numbers read from text (command options, configuration and grid values):
// the one implementation of each check.
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

namespace rvlio {

// [+-]? digits: the text of a whole number (no 1.5, no 1e3, no 0x10, no spaces).
inline bool IsIntegerText(const std::string& s) {
  const size_t begin = (!s.empty() && (s[0] == '+' || s[0] == '-')) ? 1 : 0;
  if (begin >= s.size()) return false;
  for (size_t i = begin; i < s.size(); ++i)
    if (s[i] < '0' || s[i] > '9') return false;
  return true;
}

// IsIntegerText and within the range of int64.
inline bool ParseInteger(const std::string& s, int64_t* value) {
  if (!IsIntegerText(s)) return false;
  errno = 0;
  const long long v = std::strtoll(s.c_str(), nullptr, 10);
  if (errno == ERANGE) return false;
  *value = v;
  return true;
}

// The whole text as one finite number (strtod's syntax: 1, -2.5, 1e-3).
inline bool ParseNumber(const std::string& text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return !text.empty() && *end == '\0' && std::isfinite(*value);
}

}  // namespace rvlio

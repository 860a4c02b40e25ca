#pragma once
// A CSV field as the experiment tables write it: quoted (with doubled quotes)
// only when it holds a comma, a quote or a line break.
#include <string>

namespace rvlio::experiments {

inline std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

}  // namespace rvlio::experiments

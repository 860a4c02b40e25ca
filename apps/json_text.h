#pragma once
// JSON text for the tool's outputs. Configuration strings come from the user
// (--set, YAML files, bag topics) and need not be valid UTF-8; nlohmann's
// default dump throws on such bytes, so every output replaces them (U+FFFD).
#include <string>

#include <nlohmann/json.hpp>

namespace rvlio::cli {

inline std::string JsonText(const nlohmann::json& j, int indent = 2) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace rvlio::cli

#pragma once
// The resolved configuration as JSON (summary.json "config", refine's
// checkpoint fingerprint, Python's Config.to_dict): the I/O layer's writer of
// what config.h visits. Private: JSON stays out of the public headers
// (docs/library.md).
#include <cmath>
#include <type_traits>
#include <utility>

#include <nlohmann/json.hpp>

#include "rvlio/config/config.h"

namespace rvlio {
namespace config_detail {

class JsonVisitor {
 public:
  template <typename T>
  void Field(const char* name, T& value, const Spec&) {
    if constexpr (std::is_floating_point_v<T>) {
      json[name] = std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
    } else if constexpr (std::is_enum_v<T>) {
      json[name] = EnumName(value);
    } else {
      json[name] = value;
    }
  }
  template <typename Sub>
  void Section(const char* name, Sub& sub) {
    JsonVisitor inner;
    sub.Visit(inner);
    json[name] = std::move(inner.json);
  }
  nlohmann::json json = nlohmann::json::object();
};

}  // namespace config_detail

// The resolved configuration as a JSON object (summary.json). Non-finite
// doubles become null.
template <class Opts>
nlohmann::json ToJson(const Opts& options) {
  Opts copy = options;
  config_detail::JsonVisitor v;
  copy.Visit(v);
  return std::move(v.json);
}

}  // namespace rvlio

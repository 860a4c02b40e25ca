#pragma once
// Options reflection. Every module's Options struct lists its fields once, in
// a `template <class V> void Visit(V& v)` member:
//
//   v.Field("eps0", eps0, Spec().Range(0.0, 1.0).Help("SCV threshold on |u . n_alpha|"));
//   v.Section("rv", rv);   // a nested Options struct
//
// io/ walks the same list to load YAML, apply `--set a.b=value`, reject
// unknown keys and print the resolved configuration; ValidateFields() below
// checks ranges and choices. Supported field types: bool, int, int64_t,
// double, std::string, std::array<double, N>.
#include <array>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "rvlio/common/status.h"

namespace rvlio {

struct Spec {
  std::string unit;
  std::string help;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;
  std::vector<std::string> choices;  // for strings; empty means any value

  Spec& Unit(std::string u) { unit = std::move(u); return *this; }
  Spec& Help(std::string h) { help = std::move(h); return *this; }
  Spec& Range(double lo, double hi) { min = lo; max = hi; return *this; }
  Spec& Min(double lo) { min = lo; return *this; }
  Spec& Positive() { min = 0.0; min_exclusive = true; return *this; }
  Spec& Choices(std::vector<std::string> c) { choices = std::move(c); return *this; }
};

namespace options_detail {

inline std::string Join(const std::string& prefix, const char* name) {
  return prefix.empty() ? std::string(name) : prefix + "." + name;
}

inline std::string FormatRange(const Spec& s) {
  std::ostringstream os;
  os << (s.min_exclusive ? "(" : "[") << s.min << ", " << s.max << "]";
  return os.str();
}

// Checks numeric ranges and string choices of every field; stops at the first
// violation and names the key.
class ValidateVisitor {
 public:
  explicit ValidateVisitor(std::string prefix) : prefix_(std::move(prefix)) {}

  template <typename T>
  void Field(const char* name, T& value, const Spec& spec) {
    if (!status_.ok()) return;
    Check(Join(prefix_, name), value, spec);
  }
  template <typename Sub>
  void Section(const char* name, Sub& sub) {
    if (!status_.ok()) return;
    ValidateVisitor inner(Join(prefix_, name));
    sub.Visit(inner);
    if (!inner.status_.ok()) status_ = inner.status_;
  }
  const Status& status() const { return status_; }

 private:
  void CheckNumber(const std::string& key, double x, const Spec& s) {
    const bool below = s.min_exclusive ? !(x > s.min) : !(x >= s.min);
    if (below || !(x <= s.max)) {
      std::ostringstream os;
      os << key << " = " << x << " is out of range " << FormatRange(s);
      status_ = Status::InvalidInput(os.str());
    }
  }
  template <typename T>
  void Check(const std::string& key, const T& value, const Spec& s) {
    if constexpr (std::is_same_v<T, bool>) {
      (void)key; (void)value; (void)s;
    } else if constexpr (std::is_arithmetic_v<T>) {
      CheckNumber(key, static_cast<double>(value), s);
    } else if constexpr (std::is_same_v<T, std::string>) {
      if (s.choices.empty()) return;
      for (const auto& c : s.choices) if (c == value) return;
      std::string list;
      for (const auto& c : s.choices) list += (list.empty() ? "" : "|") + c;
      status_ = Status::InvalidInput(key + " = '" + value + "' is not one of " + list);
    } else {
      for (size_t i = 0; i < value.size() && status_.ok(); ++i)
        CheckNumber(key + "[" + std::to_string(i) + "]", value[i], s);
    }
  }
  std::string prefix_;
  Status status_;
};

}  // namespace options_detail

// Range and choice validation of every field of `options`, with key names
// prefixed by `prefix` (e.g. "rv").
template <typename Options>
Status ValidateFields(Options& options, const std::string& prefix = "") {
  options_detail::ValidateVisitor v(prefix);
  options.Visit(v);
  return v.status();
}

}  // namespace rvlio

#pragma once
// Options reflection. Every module's Options struct lists its fields once, in
// a `template <class V> void Visit(V& v)` member:
//
//   v.Field("eps0", eps0, Spec().Range(0.0, 1.0).Help("SCV threshold on |u . n_alpha|"));
//   v.Section("rv", rv);   // a nested Options struct
//
// config/ walks the same list to load YAML, apply `--set a.b=value`, reject
// unknown keys and print the resolved configuration; ValidateFields() below
// checks ranges and choices. Supported field types: bool, int, int64_t,
// double, std::string, std::array<double, N>, and enums that list their
// configuration names in EnumNames (below).
//
// A renamed key stays readable for one release: the struct that holds it
// lists the old and new names of its own fields in
//
//   static constexpr DeprecatedName kDeprecatedNames[] = {{"huber_delta", "refine_huber_delta"}};
//
// and the config layer (config/config.h) then accepts the old name for the new
// field, with one warning line naming both.
#include <array>
#include <cstdint>
#include <iterator>
#include <limits>
#include <ostream>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "rvlio/common/check.h"
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

// An enum is a field type when EnumNames<E> lists its values with the names
// the configuration uses (YAML, --set, the dump, summary.json):
//
//   template <> struct EnumNames<Backend> {
//     static constexpr std::pair<Backend, const char*> kNames[] = {
//         {Backend::kIeskf, "ieskf"}, {Backend::kSmoother, "smoother"}};
//   };
//
// The name is parsed once, when the configuration is read; the code then
// compares enum values. Give the field Spec().Choices(EnumChoices<E>()).
template <class E>
struct EnumNames {};

namespace options_detail {
template <class E, class = void>
struct IsNamedEnum : std::false_type {};
template <class E>
struct IsNamedEnum<E, std::void_t<decltype(EnumNames<E>::kNames)>> : std::is_enum<E> {};
}  // namespace options_detail

template <class E>
constexpr bool kIsNamedEnum = options_detail::IsNamedEnum<E>::value;

template <class E>
const char* EnumName(E value) {
  for (const auto& [v, name] : EnumNames<E>::kNames)
    if (v == value) return name;
  return "?";
}

// False (and *out untouched) when `name` is none of E's names.
template <class E>
bool ParseEnum(const std::string& name, E* out) {
  for (const auto& [v, n] : EnumNames<E>::kNames)
    if (name == n) {
      *out = v;
      return true;
    }
  return false;
}

template <class E>
std::vector<std::string> EnumChoices() {
  std::vector<std::string> names;
  for (const auto& [v, n] : EnumNames<E>::kNames) names.emplace_back(n);
  return names;
}

// A named enum compares with and prints as its configuration name (tests,
// messages).
template <class E, std::enable_if_t<kIsNamedEnum<E>, int> = 0>
bool operator==(E value, const std::string& name) {
  return name == EnumName(value);
}
template <class E, std::enable_if_t<kIsNamedEnum<E>, int> = 0>
std::ostream& operator<<(std::ostream& os, E value) {
  return os << EnumName(value);
}

struct DeprecatedName {
  const char* old_name;  // accepted with a warning
  const char* new_name;  // the field it sets
};

namespace options_detail {

template <class T, class = void>
struct HasDeprecatedNames : std::false_type {};
template <class T>
struct HasDeprecatedNames<T, std::void_t<decltype(T::kDeprecatedNames)>> : std::true_type {};
template <class T, class = void>
struct HasMovedKeys : std::false_type {};
template <class T>
struct HasMovedKeys<T, std::void_t<decltype(T::kMovedKeys)>> : std::true_type {};

}  // namespace options_detail

// The renamed keys of one Options struct (empty for most).
template <class T>
std::vector<DeprecatedName> DeprecatedNamesOf() {
  if constexpr (options_detail::HasDeprecatedNames<T>::value) {
    return std::vector<DeprecatedName>(std::begin(T::kDeprecatedNames),
                                       std::end(T::kDeprecatedNames));
  } else {
    return {};
  }
}

// The keys of a root Options struct that moved to another section, as dotted
// paths {"refine.rounds", "refine.rounds"} (kMovedKeys; empty for most).
template <class T>
std::vector<DeprecatedName> MovedKeysOf() {
  if constexpr (options_detail::HasMovedKeys<T>::value) {
    return std::vector<DeprecatedName>(std::begin(T::kMovedKeys), std::end(T::kMovedKeys));
  } else {
    return {};
  }
}

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
    if constexpr (std::is_same_v<T, bool> || std::is_enum_v<T>) {
      (void)key; (void)value; (void)s;  // enums: checked when parsed (config/config.h)
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

namespace options_detail {

// Visits a source struct; copies its section `name` into *target when the
// section has Target's type.
template <class Target>
class SectionFinder {
 public:
  SectionFinder(const char* name, Target* target) : name_(name), target_(target) {}
  template <typename T>
  void Field(const char*, T&, const Spec&) {}
  template <typename Sub>
  void Section(const char* name, Sub& sub) {
    if constexpr (std::is_same_v<Sub, Target>) {
      if (name_ != name) return;
      *target_ = sub;
      found = true;
    }
  }
  bool found = false;

 private:
  std::string name_;
  Target* target_;
};

// Visits a target struct; fills each of its sections from `source`.
template <class Source>
class SectionCopier {
 public:
  explicit SectionCopier(const Source& source) : source_(source) {}
  template <typename T>
  void Field(const char*, T&, const Spec&) {}
  template <typename Sub>
  void Section(const char* name, Sub& sub) {
    Source copy = source_;  // Visit is not const
    SectionFinder<Sub> finder(name, &sub);
    copy.Visit(finder);
    RVLIO_CHECK_MSG(finder.found, "CopySections: the source has no such section");
  }

 private:
  const Source& source_;
};

}  // namespace options_detail

// Fills every top-level section of *target with the section of the same name
// and type of `source`, through the reflection: a module whose options are a
// selection of the configuration's sections (e.g. the sliding window's, from
// OdometryOptions) gets them without a hand-written copy per field. Each
// section of the target must exist in the source (checked); the target's own
// top-level fields are left as they are.
template <class Source, class Target>
void CopySections(const Source& source, Target* target) {
  options_detail::SectionCopier<Source> copier(source);
  target->Visit(copier);
}

// Range and choice validation of every field of `options`, with key names
// prefixed by `prefix` (e.g. "rv").
template <typename Options>
Status ValidateFields(Options& options, const std::string& prefix = "") {
  options_detail::ValidateVisitor v(prefix);
  options.Visit(v);
  return v.status();
}

}  // namespace rvlio

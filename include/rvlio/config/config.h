#pragma once
// Configuration loading (docs/design.md "The command-line contract"): built-in defaults, then each
// `--config` YAML file in order (later files win), then each
// `--set a.b=value` override, then validation. Works on any Options struct
// with a `template <class V> void Visit(V&)` member (common/options.h), so new
// fields need no change here. Every error is Status::InvalidInput (exit 2) with
// a one-line message that names the key and the file (or "--set").
//
// yaml-cpp stays in config.cpp: files and override values are parsed there
// into the plain YamlNode tree (yaml_tree.h), which the visitors below walk.
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>


#include "rvlio/common/options.h"
#include "rvlio/common/status.h"
#include "rvlio/config/configuration.h"
#include "rvlio/config/yaml_tree.h"

namespace rvlio {

// Where each key got its value: dotted key -> "file.yaml:LINE" or "--set".
// Keys that keep their built-in default are absent.
using ConfigSources = std::map<std::string, std::string>;

namespace config_detail {

// A parsed YAML document (yaml_tree.h).
using Node = YamlNode;

// Parses a whole file (top level must be a mapping or empty). Errors name the
// file, and the line for syntax errors and duplicate keys. A document over the
// value limit is an error, unless `keep_over_budget`: then the root carries
// the error in over_budget for the caller to report after FirstUnknownKey.
StatusOr<Node> ParseYamlFile(const std::string& path, bool keep_over_budget = false);
// Parses YAML text; `source` names it in error messages.
StatusOr<Node> ParseYamlText(const std::string& text, const std::string& source,
                             bool keep_over_budget = false);
// The UnknownKey error of the first key of `n` (dotted under `prefix`) that is
// neither one of `known_keys` nor a section holding some of them.
Status FirstUnknownKey(const Node& n, const std::string& prefix, const std::string& source,
                       const std::vector<std::string>& known_keys);
// "a.b.c=value" -> {a: {b: {c: <value parsed as a YAML scalar or flow sequence>}}}.
StatusOr<Node> ParseOverride(const std::string& assignment);

// "file.yaml:12", or just `source` when the line is unknown (0).
std::string Where(const std::string& source, int line);

// Leaf conversions: `key` and `where` only serve the error message.
Status Read(const Node& n, const std::string& key, const std::string& where, bool* out);
Status Read(const Node& n, const std::string& key, const std::string& where, std::string* out);
Status Read(const Node& n, const std::string& key, const std::string& where, double* out);
Status ReadInteger(const Node& n, const std::string& key, const std::string& where, int64_t min,
                   int64_t max, int64_t* out);
Status ReadNumbers(const Node& n, const std::string& key, const std::string& where, size_t count,
                   double* out);

Status NotASection(const Node& n, const std::string& key, const std::string& where);
// "WHERE: KEY = 'VALUE' is not one of A|B" (the message of a bad choice).
Status NotOneOf(const std::string& key, const std::string& where, const std::string& value,
                const std::vector<std::string>& choices);
// Moves every key of `moved` that `root` gives under its former dotted name
// ({"refine.rounds", "refine.rounds"}) to its new one, creating the
// sections on the way; one DeprecationWarning each into *deprecations (may be
// null). BothNames when the mapping gives both names.
Status RelocateMovedKeys(Node* root, const std::vector<DeprecatedName>& moved,
                         const std::string& source, std::vector<std::string>* deprecations);
// A mapping that gives a key under both its deprecated and its new name.
Status BothNames(const std::string& old_key, const std::string& new_key, const std::string& where);
// "WHERE: OLD is deprecated, use NEW (the old name goes in the next release)".
std::string DeprecationWarning(const std::string& old_key, const std::string& new_key,
                               const std::string& where);
Status UnknownKey(const std::string& key, const std::string& where,
                  const std::vector<std::string>& known_keys);

template <typename T>
Status ReadField(const Node& n, const std::string& key, const std::string& where, T* out) {
  if constexpr (std::is_same_v<T, bool> || std::is_same_v<T, std::string> ||
                std::is_same_v<T, double>) {
    return Read(n, key, where, out);
  } else if constexpr (std::is_floating_point_v<T>) {
    double x = 0.0;
    Status s = Read(n, key, where, &x);
    if (s.ok()) *out = static_cast<T>(x);
    return s;
  } else if constexpr (std::is_enum_v<T>) {
    static_assert(kIsNamedEnum<T>, "enum fields need EnumNames (common/options.h)");
    std::string name;
    Status s = Read(n, key, where, &name);
    if (s.ok() && !ParseEnum(name, out)) s = NotOneOf(key, where, name, EnumChoices<T>());
    return s;
  } else if constexpr (std::is_integral_v<T>) {
    using Limits = std::numeric_limits<T>;
    constexpr int64_t kMin = static_cast<int64_t>(Limits::min());  // 0 for unsigned types
    constexpr int64_t kMax = Limits::digits >= 63 ? std::numeric_limits<int64_t>::max()
                                                  : static_cast<int64_t>(Limits::max());
    int64_t x = 0;
    Status s = ReadInteger(n, key, where, kMin, kMax, &x);
    if (s.ok()) *out = static_cast<T>(x);
    return s;
  } else {
    static_assert(std::is_same_v<typename T::value_type, double>,
                  "config fields are bool, integers, double, std::string or std::array<double, N>");
    return ReadNumbers(n, key, where, out->size(), out->data());
  }
}

// Every dotted key of an Options struct: leaves (with their Spec) and sections.
class KeyCollector {
 public:
  explicit KeyCollector(std::string prefix = "") : prefix_(std::move(prefix)) {}
  template <typename T>
  void Field(const char* name, T&, const Spec& spec) {
    leaves.emplace_back(options_detail::Join(prefix_, name), spec);
  }
  template <typename Sub>
  void Section(const char* name, Sub& sub) {
    KeyCollector inner(options_detail::Join(prefix_, name));
    sub.Visit(inner);
    sections.push_back(inner.prefix_);
    for (auto& l : inner.leaves) leaves.push_back(std::move(l));
    for (auto& s : inner.sections) sections.push_back(std::move(s));
  }
  std::vector<std::pair<std::string, Spec>> leaves;
  std::vector<std::string> sections;

 private:
  std::string prefix_;
};

// Copies the values of one mapping node into the fields it names; any key of
// the mapping that no field or section consumed is an error.
class ApplyVisitor {
 public:
  // renamed: the deprecated names of the struct this mapping fills;
  // deprecations (may be null) receives one warning per old name used.
  ApplyVisitor(const Node& map, std::string prefix, const std::string& source,
               const std::vector<std::string>& known_keys, ConfigSources* sources,
               std::vector<DeprecatedName> renamed = {},
               std::vector<std::string>* deprecations = nullptr)
      : map_(map),
        prefix_(std::move(prefix)),
        source_(source),
        known_keys_(known_keys),
        sources_(sources),
        renamed_(std::move(renamed)),
        deprecations_(deprecations),
        used_(map.keys.size(), false) {}

  template <typename T>
  void Field(const char* name, T& value, const Spec&) {
    const size_t i = Take(name);
    if (i == kAbsent) return;
    const std::string key = options_detail::Join(prefix_, name);
    const std::string where = Where(source_, map_.key_lines[i]);
    status_ = ReadField(map_.items[i], key, where, &value);
    if (status_.ok() && sources_ != nullptr) (*sources_)[key] = where;
  }
  template <typename Sub>
  void Section(const char* name, Sub& sub) {
    const size_t i = Take(name);
    if (i == kAbsent || map_.items[i].kind == Node::Kind::kNull) return;  // "rv:" alone: no change
    const std::string key = options_detail::Join(prefix_, name);
    if (map_.items[i].kind != Node::Kind::kMap) {
      status_ = NotASection(map_.items[i], key, Where(source_, map_.key_lines[i]));
      return;
    }
    ApplyVisitor inner(map_.items[i], key, source_, known_keys_, sources_,
                       DeprecatedNamesOf<Sub>(), deprecations_);
    sub.Visit(inner);
    status_ = inner.Finish();
  }
  // The first error, or the first key nobody consumed.
  Status Finish() const {
    if (!status_.ok()) return status_;
    for (size_t i = 0; i < used_.size(); ++i)
      if (!used_[i])
        return UnknownKey(options_detail::Join(prefix_, map_.keys[i].c_str()),
                          Where(source_, map_.key_lines[i]), known_keys_);
    return Status::Ok();
  }

 private:
  static constexpr size_t kAbsent = static_cast<size_t>(-1);
  size_t Find(const char* name) const {
    for (size_t i = 0; i < map_.keys.size(); ++i)
      if (map_.keys[i] == name) return i;
    return kAbsent;
  }
  // Index of key `name`, or of a deprecated name of it, in the mapping
  // (marked as consumed), or kAbsent.
  size_t Take(const char* name) {
    if (!status_.ok()) return kAbsent;
    size_t i = Find(name);
    for (const DeprecatedName& d : renamed_) {
      if (std::string(d.new_name) != name) continue;
      const size_t old = Find(d.old_name);
      if (old == kAbsent) continue;
      if (i != kAbsent) {
        status_ = BothNames(options_detail::Join(prefix_, d.old_name),
                            options_detail::Join(prefix_, name), Where(source_, map_.key_lines[old]));
        return kAbsent;
      }
      i = old;
      if (deprecations_ != nullptr)
        deprecations_->push_back(DeprecationWarning(options_detail::Join(prefix_, d.old_name),
                                                    options_detail::Join(prefix_, name),
                                                    Where(source_, map_.key_lines[old])));
    }
    if (i != kAbsent) used_[i] = true;
    return i;
  }
  const Node& map_;
  std::string prefix_;
  const std::string& source_;
  const std::vector<std::string>& known_keys_;
  ConfigSources* sources_;
  std::vector<DeprecatedName> renamed_;
  std::vector<std::string>* deprecations_;
  std::vector<bool> used_;
  Status status_;
};

// One resolved key per line, nested like the struct, with comments.
class DumpVisitor {
 public:
  explicit DumpVisitor(int indent = 0) : indent_(indent) {}
  template <typename T>
  void Field(const char* name, T& value, const Spec& spec) {
    lines_.push_back({Indent() + name + ": " + FormatValue(value), Comment(spec)});
  }
  template <typename Sub>
  void Section(const char* name, Sub& sub) {
    if (indent_ == 0 && !lines_.empty()) lines_.push_back({"", ""});
    lines_.push_back({Indent() + name + ":", ""});
    DumpVisitor inner(indent_ + 2);
    sub.Visit(inner);
    for (auto& l : inner.lines_) lines_.push_back(std::move(l));
  }
  std::string Text() const;

 private:
  static std::string FormatValue(bool b) { return b ? "true" : "false"; }
  static std::string FormatValue(const std::string& s) { return FormatString(s); }
  template <typename T>
  static std::string FormatValue(const T& v) {
    if constexpr (std::is_enum_v<T>) {
      return FormatString(EnumName(v));
    } else if constexpr (std::is_floating_point_v<T>) {
      return FormatDouble(static_cast<double>(v));
    } else if constexpr (std::is_integral_v<T>) {
      return std::to_string(v);
    } else {
      std::string s = "[";
      for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + FormatDouble(v[i]);
      return s + "]";
    }
  }
  static std::string FormatDouble(double x);              // shortest text that reads back exactly
  static std::string FormatString(const std::string& s);  // plain or double-quoted
  static std::string Comment(const Spec& spec);           // "[unit] help; one of a | b"
  std::string Indent() const { return std::string(static_cast<size_t>(indent_), ' '); }

  int indent_;
  std::vector<std::pair<std::string, std::string>> lines_;  // text, comment
};

// Keys (leaves and sections) used for "did you mean" suggestions.
template <class Opts>
std::vector<std::string> KnownKeys(const Opts& options) {
  Opts copy = options;
  KeyCollector c;
  copy.Visit(c);
  std::vector<std::string> keys;
  for (const auto& l : c.leaves) keys.push_back(l.first);
  for (const auto& s : c.sections) keys.push_back(s);
  return keys;
}

// Applies the mapping `root` to a copy of `options`; on success the copy
// replaces `options` (a failed file leaves the options untouched).
// Deprecated names used are appended to *deprecations (may be null), one
// warning each.
template <class Opts>
Status ApplyNode(Opts& options, const Node& root, const std::string& source,
                 ConfigSources* sources, std::vector<std::string>* deprecations = nullptr) {
  if (root.kind == Node::Kind::kNull) return Status::Ok();
  RVLIO_CHECK(root.kind == Node::Kind::kMap);
  const std::vector<std::string> known = KnownKeys(options);
  Opts copy = options;
  ConfigSources new_sources;
  std::vector<std::string> new_deprecations;
  const std::vector<DeprecatedName> moved = MovedKeysOf<Opts>();
  Node relocated;
  if (!moved.empty()) {
    relocated = root;
    if (Status s = RelocateMovedKeys(&relocated, moved, source, &new_deprecations); !s.ok())
      return s;
  }
  ApplyVisitor v(moved.empty() ? root : relocated, "", source, known, &new_sources,
                 DeprecatedNamesOf<Opts>(), &new_deprecations);
  copy.Visit(v);
  Status s = v.Finish();
  if (!s.ok()) return s;
  options = std::move(copy);
  if (sources != nullptr)
    for (auto& kv : new_sources) (*sources)[kv.first] = std::move(kv.second);
  if (deprecations != nullptr)
    for (auto& w : new_deprecations) deprecations->push_back(std::move(w));
  return Status::Ok();
}

}  // namespace config_detail

// Every leaf key of an Options struct in visiting order, e.g. "rv.eps0".
template <class Opts>
std::vector<std::string> ListKeys(const Opts& options) {
  Opts copy = options;
  config_detail::KeyCollector c;
  copy.Visit(c);
  std::vector<std::string> keys;
  for (const auto& l : c.leaves) keys.push_back(l.first);
  return keys;
}

namespace config_detail {
// A document over the value limit: an unknown key it holds is the error to
// report (a large section under a misspelt name), else the limit itself.
template <class Opts>
Status CheckOverBudget(const Opts& options, const Node& root, const std::string& source) {
  if (root.over_budget.empty()) return Status::Ok();
  if (Status s = FirstUnknownKey(root, "", source, ListKeys(options)); !s.ok()) return s;
  return Status::InvalidInput(root.over_budget);
}
}  // namespace config_detail

// Overlays one YAML file onto `options` (only the keys it contains). Records
// in `sources` (if given) where each key came from.
// Deprecated names used add a warning each to *deprecations (may be null).
template <class Opts>
Status ApplyYamlFile(Opts& options, const std::string& path, ConfigSources* sources = nullptr,
                     std::vector<std::string>* deprecations = nullptr) {
  StatusOr<config_detail::Node> root = config_detail::ParseYamlFile(path, true);
  if (!root.ok()) return root.status();
  if (Status s = config_detail::CheckOverBudget(options, *root, path); !s.ok()) return s;
  return config_detail::ApplyNode(options, *root, path, sources, deprecations);
}

// Same for YAML text; `source` names it in messages.
template <class Opts>
Status ApplyYamlText(Opts& options, const std::string& text, const std::string& source,
                     ConfigSources* sources = nullptr) {
  StatusOr<config_detail::Node> root = config_detail::ParseYamlText(text, source, true);
  if (!root.ok()) return root.status();
  if (Status s = config_detail::CheckOverBudget(options, *root, source); !s.ok()) return s;
  return config_detail::ApplyNode(options, *root, source, sources);
}

// Applies one `--set` argument "a.b=value"; value is a YAML scalar or flow
// sequence ("extrinsics.imu_T_lidar.translation=[0.1,0,0.05]").
template <class Opts>
Status ApplyOverride(Opts& options, const std::string& assignment,
                     ConfigSources* sources = nullptr,
                     std::vector<std::string>* deprecations = nullptr) {
  StatusOr<config_detail::Node> root = config_detail::ParseOverride(assignment);
  if (!root.ok()) return root.status();
  return config_detail::ApplyNode(options, *root, "--set", sources, deprecations);
}

// Prefixes a validation message with the source of the key it names, e.g.
// "foo.yaml:3: rv.eps0 = 2 is out of range [0, 1]"; when it names several keys
// it also lists where each came from. Messages naming no known key pass as is.
Status AttributeToSources(const Status& status, const std::vector<std::string>& leaf_keys,
                          const ConfigSources& sources);

// Defaults, then files in order, then overrides in order, then Opts::Validate().
// warnings (may be null) receives one line per deprecated key name used
// (the caller prints them; the library does not).
template <class Opts>
StatusOr<Opts> LoadOptions(const std::vector<std::string>& config_files,
                           const std::vector<std::string>& set_overrides,
                           ConfigSources* sources_out = nullptr,
                           std::vector<std::string>* warnings = nullptr) {
  Opts options;
  ConfigSources sources;
  std::vector<std::string> deprecations;
  for (const auto& f : config_files) {
    Status s = ApplyYamlFile(options, f, &sources, &deprecations);
    if (!s.ok()) return s;
  }
  for (const auto& o : set_overrides) {
    Status s = ApplyOverride(options, o, &sources, &deprecations);
    if (!s.ok()) return s;
  }
  Status s = options.Validate();
  if (!s.ok()) return AttributeToSources(s, ListKeys(options), sources);
  if (sources_out != nullptr) *sources_out = std::move(sources);
  if (warnings != nullptr)
    for (auto& w : deprecations) warnings->push_back(std::move(w));
  return options;
}

// The odometry configuration of `rvlio run`, `refine`, `compare`, `ablate`.
// warnings (may be null): one line per deprecated key name used.
StatusOr<Configuration> LoadConfig(const std::vector<std::string>& config_files,
                                     const std::vector<std::string>& set_overrides,
                                     std::vector<std::string>* warnings = nullptr);

// The resolved configuration as YAML: every key, nested like the struct, with
// units and help as comments. ApplyYamlText of the result restores `options`
// exactly (doubles are written with enough digits).
template <class Opts>
std::string DumpYaml(const Opts& options) {
  Opts copy = options;
  config_detail::DumpVisitor v;
  copy.Visit(v);
  return v.Text();
}

}  // namespace rvlio

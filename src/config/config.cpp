#include "rvlio/config/config.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "rvlio/common/number_text.h"

namespace rvlio {
namespace config_detail {
namespace {

std::string Quote(const std::string& text) { return "'" + text + "'"; }

// What a node holds, for "expected X, got Y" messages.
std::string Describe(const Node& n) {
  switch (n.kind) {
    case Node::Kind::kNull:
      return "an empty value";
    case Node::Kind::kSequence:
      return "a list";
    case Node::Kind::kMap:
      return "a mapping";
    case Node::Kind::kScalar:
      break;
  }
  return Quote(n.scalar);
}

Status Expected(const Node& n, const std::string& key, const std::string& where,
                const std::string& what) {
  return Status::InvalidInput(key + " in " + where + ": expected " + what + ", got " + Describe(n));
}

bool IsDigits(const std::string& s, size_t begin, size_t end) {
  if (begin >= end) return false;
  for (size_t i = begin; i < end; ++i)
    if (s[i] < '0' || s[i] > '9') return false;
  return true;
}

// A decimal number: [+-]? (d+ (. d*)? | . d+) ([eE] [+-]? d+)?
bool IsDecimalText(const std::string& s) {
  size_t i = (!s.empty() && (s[0] == '+' || s[0] == '-')) ? 1 : 0;
  const size_t e = std::min(s.find_first_of("eE"), s.size());
  const size_t dot = s.find('.', i);
  const size_t mant_end = std::min(dot, e);
  bool mantissa = IsDigits(s, i, mant_end);
  if (dot < e) {
    const bool frac = dot + 1 == e || IsDigits(s, dot + 1, e);
    mantissa = (mantissa && frac) || (dot == i && IsDigits(s, dot + 1, e));
  }
  if (!mantissa) return false;
  if (e == s.size()) return true;
  size_t j = e + 1;
  if (j < s.size() && (s[j] == '+' || s[j] == '-')) ++j;
  return IsDigits(s, j, s.size());
}

bool ParseDouble(const std::string& s, double* out) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (const char* t : {".inf", ".Inf", ".INF", "+.inf", "+.Inf", "+.INF"})
    if (s == t) {
      *out = kInf;
      return true;
    }
  for (const char* t : {"-.inf", "-.Inf", "-.INF"})
    if (s == t) {
      *out = -kInf;
      return true;
    }
  for (const char* t : {".nan", ".NaN", ".NAN"})
    if (s == t) {
      *out = std::numeric_limits<double>::quiet_NaN();
      return true;
    }
  if (!IsDecimalText(s)) return false;
  *out = std::strtod(s.c_str(), nullptr);
  return true;
}

int LineOf(const YAML::Node& y) { return y.Mark().line >= 0 ? y.Mark().line + 1 : 0; }

// Bounds of a document. A configuration is a few hundred values nested a few
// levels deep; the bounds stop a recursive alias ("a: &x [*x]", endless
// recursion) and nested aliases that expand exponentially ("billion laughs").
constexpr int kMaxDepth = 64;
constexpr size_t kMaxValues = 10000;  // config/default.yaml has 84

// When the budget runs out, the rest of the document converts to nulls (keys
// are kept) and the error waits in Node::over_budget, so that a loader that
// knows its keys can first name an unknown one (a large unknown section is
// a likelier mistake than an alias bomb).
struct ConvertBudget {
  size_t values_left = kMaxValues;
  std::string error;  // the first value over the budget
};

// yaml-cpp document -> Node; `path` is the dotted key of `y` for messages.
Status Convert(const YAML::Node& y, const std::string& path, const std::string& source, int depth,
               ConvertBudget* budget, Node* out) {
  out->line = LineOf(y);
  // The key of the top-level entry: deep paths ("a[0][0]...") would be unreadable.
  const auto what = [&path] {
    return path.empty() ? std::string("top level") : path.substr(0, path.find_first_of(".["));
  };
  if (depth > kMaxDepth)
    return Status::InvalidInput(what() + " in " + Where(source, out->line) +
                                ": nested deeper than " + std::to_string(kMaxDepth) +
                                " levels (a recursive alias?)");
  if (budget->values_left == 0) {
    if (budget->error.empty())
      budget->error = what() + " in " + Where(source, out->line) + ": more than " +
                      std::to_string(kMaxValues) + " values (aliases expanding exponentially?)";
    out->kind = Node::Kind::kNull;
    return Status::Ok();
  }
  --budget->values_left;
  if (y.IsNull()) {
    out->kind = Node::Kind::kNull;
  } else if (y.IsScalar()) {
    out->kind = Node::Kind::kScalar;
    out->scalar = y.Scalar();
  } else if (y.IsSequence()) {
    out->kind = Node::Kind::kSequence;
    size_t i = 0;  // iterators: y[i] costs a search per element in yaml-cpp
    for (const YAML::Node& item : y) {
      out->items.emplace_back();
      Status s = Convert(item, path + "[" + std::to_string(i++) + "]", source, depth + 1, budget,
                         &out->items.back());
      if (!s.ok()) return s;
    }
  } else if (y.IsMap()) {
    out->kind = Node::Kind::kMap;
    std::set<std::string> seen;  // duplicate keys, without a quadratic search
    for (const auto& kv : y) {
      const int line = LineOf(kv.first);
      if (!kv.first.IsScalar())
        return Status::InvalidInput((path.empty() ? "top level" : path) + " in " +
                                    Where(source, line) + ": keys must be plain names");
      const std::string key = kv.first.Scalar();
      const std::string full = options_detail::Join(path, key.c_str());
      if (!seen.insert(key).second)
        return Status::InvalidInput(full + ": duplicate key in " + Where(source, line));
      out->keys.push_back(key);
      out->key_lines.push_back(line);
      out->items.emplace_back();
      Status s = Convert(kv.second, full, source, depth + 1, budget, &out->items.back());
      if (!s.ok()) return s;
    }
  }
  return Status::Ok();
}

// Parses YAML text; a syntax error becomes `on_error(exception)`.
template <typename OnError>
StatusOr<Node> LoadYaml(const std::string& text, const std::string& source, OnError on_error) {
  YAML::Node y;
  try {
    y = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    return on_error(e);
  }
  Node root;
  ConvertBudget budget;
  Status s = Convert(y, "", source, 0, &budget, &root);
  if (!s.ok()) return s;
  root.over_budget = budget.error;
  return root;
}

std::string Trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

std::vector<std::string> SplitKey(const std::string& key) {
  std::vector<std::string> parts;
  size_t begin = 0;
  while (true) {
    const size_t dot = key.find('.', begin);
    parts.push_back(key.substr(begin, dot - begin));
    if (dot == std::string::npos) return parts;
    begin = dot + 1;
  }
}

size_t Levenshtein(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string LastSegment(const std::string& key) {
  const size_t dot = key.rfind('.');
  return dot == std::string::npos ? key : key.substr(dot + 1);
}

std::string Parent(const std::string& key) {
  const size_t dot = key.rfind('.');
  return dot == std::string::npos ? "" : key.substr(0, dot);
}

// The known key closest to `key`: a small edit of the whole key, the same (or
// nearly the same) name in another section, or else the only key of the same
// section whose name starts with the given one ("smoother.window").
std::string ClosestKey(const std::string& key, const std::vector<std::string>& known) {
  const std::string last = LastSegment(key);
  const size_t threshold = std::max<size_t>(1, std::min<size_t>(3, last.size() / 3));
  std::string best;
  size_t best_score = threshold + 1;
  for (const auto& k : known) {
    const size_t score = std::min(Levenshtein(key, k), Levenshtein(last, LastSegment(k)) + 1);
    if (score < best_score) {
      best_score = score;
      best = k;
    }
  }
  if (!best.empty() || last.size() < 3) return best;
  std::vector<std::string> prefixed;
  for (const auto& k : known)
    if (Parent(k) == Parent(key) && LastSegment(k).rfind(last, 0) == 0) prefixed.push_back(k);
  return prefixed.size() == 1 ? prefixed[0] : "";
}

bool IsKeyChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

// Position of `key` as a whole dotted word in `text` (npos if absent).
size_t FindKey(const std::string& text, const std::string& key) {
  for (size_t pos = text.find(key); pos != std::string::npos; pos = text.find(key, pos + 1)) {
    const size_t end = pos + key.size();
    const bool start_ok = pos == 0 || (!IsKeyChar(text[pos - 1]) && text[pos - 1] != '.');
    const bool longer = end < text.size() &&
                        (IsKeyChar(text[end]) ||
                         (text[end] == '.' && end + 1 < text.size() && IsKeyChar(text[end + 1])));
    if (start_ok && !longer) return pos;
  }
  return std::string::npos;
}

// A string that every YAML reader reads back as this same string unquoted.
bool IsPlainSafe(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '/' || s[0] == '_'))
    return false;
  for (char c : s)
    if (!IsKeyChar(c) && c != '/' && c != '.' && c != '-') return false;
  for (const char* r : {"true", "false", "True", "False", "TRUE", "FALSE", "null", "Null", "NULL",
                        "yes",  "no",    "Yes",  "No",    "YES",  "NO",    "on",   "off",  "On",
                        "Off",  "ON",    "OFF",  "y",     "n",    "Y",     "N"})
    if (s == r) return false;
  return true;
}

std::vector<std::string> SplitDotted(const std::string& key) {
  std::vector<std::string> parts;
  size_t begin = 0;
  for (size_t dot = key.find('.'); dot != std::string::npos; dot = key.find('.', begin)) {
    parts.push_back(key.substr(begin, dot - begin));
    begin = dot + 1;
  }
  parts.push_back(key.substr(begin));
  return parts;
}

size_t KeyIndex(const Node& map, const std::string& key) {
  for (size_t i = 0; i < map.keys.size(); ++i)
    if (map.keys[i] == key) return i;
  return map.keys.size();
}

// The mapping holding the last part of `parts` (null when a section on the
// way is absent or not a mapping) and that part's index in it (its size when
// absent).
Node* ParentOf(Node* root, const std::vector<std::string>& parts, size_t* index) {
  Node* map = root;
  for (size_t p = 0; p + 1 < parts.size(); ++p) {
    const size_t i = KeyIndex(*map, parts[p]);
    if (i == map->keys.size() || map->items[i].kind != Node::Kind::kMap) return nullptr;
    map = &map->items[i];
  }
  *index = KeyIndex(*map, parts.back());
  return map;
}

// The mapping of the sections `parts` (but the last), created where absent.
StatusOr<Node*> MakeSections(Node* root, const std::vector<std::string>& parts, int line,
                             const std::string& source) {
  Node* map = root;
  std::string key;
  for (size_t p = 0; p + 1 < parts.size(); ++p) {
    key = key.empty() ? parts[p] : key + "." + parts[p];
    size_t i = KeyIndex(*map, parts[p]);
    if (i == map->keys.size()) {
      map->keys.push_back(parts[p]);
      map->key_lines.push_back(line);
      map->items.push_back(Node{});
    }
    Node& section = map->items[i];
    if (section.kind == Node::Kind::kNull) section.kind = Node::Kind::kMap;  // "refine:" alone
    if (section.kind != Node::Kind::kMap)
      return NotASection(section, key, Where(source, map->key_lines[i]));
    map = &section;
  }
  return map;
}

}  // namespace

std::string Where(const std::string& source, int line) {
  return line > 0 ? source + ":" + std::to_string(line) : source;
}

Status FirstUnknownKey(const Node& n, const std::string& prefix, const std::string& source,
                       const std::vector<std::string>& known_keys) {
  if (n.kind != Node::Kind::kMap) return Status::Ok();
  for (size_t i = 0; i < n.keys.size(); ++i) {
    const std::string key = options_detail::Join(prefix, n.keys[i].c_str());
    const bool known = std::any_of(known_keys.begin(), known_keys.end(), [&key](const std::string& k) {
      return k == key || k.rfind(key + ".", 0) == 0;
    });
    if (!known) return UnknownKey(key, Where(source, n.key_lines[i]), known_keys);
    if (Status s = FirstUnknownKey(n.items[i], key, source, known_keys); !s.ok()) return s;
  }
  return Status::Ok();
}

StatusOr<Node> ParseYamlText(const std::string& text, const std::string& source,
                             bool keep_over_budget) {
  StatusOr<Node> root = LoadYaml(text, source, [&](const YAML::Exception& e) {
    std::ostringstream os;
    os << source << ":" << e.mark.line + 1 << ":" << e.mark.column + 1
       << ": YAML syntax error: " << e.msg;
    return Status::InvalidInput(os.str());
  });
  if (!root.ok()) return root;
  if (!keep_over_budget && !root->over_budget.empty())
    return Status::InvalidInput(root->over_budget);
  const Node::Kind kind = root->kind;
  if (kind != Node::Kind::kMap && kind != Node::Kind::kNull)
    return Status::InvalidInput(source + ": expected a mapping of keys at the top level, got " +
                                Describe(*root));
  return root;
}
StatusOr<Node> ParseYamlFile(const std::string& path, bool keep_over_budget) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    return Status::InvalidInput(path + ": config file not found");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) return Status::InvalidInput(path + ": cannot read config file");
  return ParseYamlText(text.str(), path, keep_over_budget);
}

StatusOr<Node> ParseOverride(const std::string& assignment) {
  const size_t eq = assignment.find('=');
  const std::string key = Trim(assignment.substr(0, eq));
  if (eq == std::string::npos || key.empty())
    return Status::InvalidInput("--set " + Quote(assignment) +
                                ": expected KEY=VALUE, e.g. rv.eps0=0.3");
  const std::vector<std::string> parts = SplitKey(key);
  for (const auto& p : parts)
    if (p.empty() || p.find_first_of(" \t") != std::string::npos)
      return Status::InvalidInput("--set " + Quote(assignment) + ": malformed key " + Quote(key));
  const std::string text = assignment.substr(eq + 1);
  StatusOr<Node> value = LoadYaml(text, "--set", [&](const YAML::Exception& e) {
    return Status::InvalidInput(key + " in --set: cannot parse value " + Quote(text) + " (" +
                                e.msg + ")");
  });
  if (!value.ok()) return value.status();
  if (!value->over_budget.empty()) return Status::InvalidInput(value->over_budget);
  Node node = std::move(value).value();
  for (auto it = parts.rbegin(); it != parts.rend(); ++it) {
    Node map;
    map.kind = Node::Kind::kMap;
    map.keys.push_back(*it);
    map.key_lines.push_back(0);
    map.items.push_back(std::move(node));
    node = std::move(map);
  }
  return node;
}

Status Read(const Node& n, const std::string& key, const std::string& where, bool* out) {
  if (n.kind == Node::Kind::kScalar) {
    for (const char* t : {"true", "True", "TRUE"})
      if (n.scalar == t) {
        *out = true;
        return Status::Ok();
      }
    for (const char* f : {"false", "False", "FALSE"})
      if (n.scalar == f) {
        *out = false;
        return Status::Ok();
      }
  }
  return Expected(n, key, where, "true or false");
}

Status Read(const Node& n, const std::string& key, const std::string& where, std::string* out) {
  if (n.kind != Node::Kind::kScalar) return Expected(n, key, where, "a string");
  *out = n.scalar;
  return Status::Ok();
}

Status Read(const Node& n, const std::string& key, const std::string& where, double* out) {
  if (n.kind != Node::Kind::kScalar || !ParseDouble(n.scalar, out))
    return Expected(n, key, where, "a number");
  return Status::Ok();
}

Status ReadInteger(const Node& n, const std::string& key, const std::string& where, int64_t min,
                   int64_t max, int64_t* out) {
  if (n.kind != Node::Kind::kScalar || !IsIntegerText(n.scalar))
    return Expected(n, key, where, "an integer");
  errno = 0;
  const long long x = std::strtoll(n.scalar.c_str(), nullptr, 10);
  if (errno == ERANGE || x < min || x > max)
    return Expected(n, key, where,
                    "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  *out = static_cast<int64_t>(x);
  return Status::Ok();
}

Status ReadNumbers(const Node& n, const std::string& key, const std::string& where, size_t count,
                   double* out) {
  const std::string what = "a list of " + std::to_string(count) + " numbers";
  if (n.kind != Node::Kind::kSequence) return Expected(n, key, where, what);
  if (n.items.size() != count)
    return Status::InvalidInput(key + " in " + where + ": expected " + what + ", got " +
                                std::to_string(n.items.size()));
  std::vector<double> values(count);
  for (size_t i = 0; i < count; ++i) {
    Status s = Read(n.items[i], key + "[" + std::to_string(i) + "]", where, &values[i]);
    if (!s.ok()) return s;
  }
  std::copy(values.begin(), values.end(), out);
  return Status::Ok();
}

Status NotASection(const Node& n, const std::string& key, const std::string& where) {
  return Expected(n, key, where, "a section of keys");
}

Status NotOneOf(const std::string& key, const std::string& where, const std::string& value,
                const std::vector<std::string>& choices) {
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : "|") + c;
  return Status::InvalidInput(where + ": " + key + " = '" + value + "' is not one of " + list);
}

Status RelocateMovedKeys(Node* root, const std::vector<DeprecatedName>& moved,
                         const std::string& source, std::vector<std::string>* deprecations) {
  for (const DeprecatedName& m : moved) {
    const std::vector<std::string> from = SplitDotted(m.old_name), to = SplitDotted(m.new_name);
    size_t i = 0;
    Node* old_map = ParentOf(root, from, &i);
    if (old_map == nullptr || i == old_map->keys.size()) continue;
    const int line = old_map->key_lines[i];
    const std::string where = Where(source, line);
    size_t j = 0;
    if (Node* new_map = ParentOf(root, to, &j); new_map != nullptr && j < new_map->keys.size())
      return BothNames(m.old_name, m.new_name, where);
    Node value = std::move(old_map->items[i]);
    old_map->items.erase(old_map->items.begin() + static_cast<std::ptrdiff_t>(i));
    old_map->keys.erase(old_map->keys.begin() + static_cast<std::ptrdiff_t>(i));
    old_map->key_lines.erase(old_map->key_lines.begin() + static_cast<std::ptrdiff_t>(i));
    StatusOr<Node*> new_map = MakeSections(root, to, line, source);
    if (!new_map.ok()) return new_map.status();
    (*new_map)->keys.push_back(to.back());
    (*new_map)->key_lines.push_back(line);
    (*new_map)->items.push_back(std::move(value));
    if (deprecations != nullptr)
      deprecations->push_back(DeprecationWarning(m.old_name, m.new_name, where));
  }
  return Status::Ok();
}

Status BothNames(const std::string& old_key, const std::string& new_key,
                 const std::string& where) {
  return Status::InvalidInput(old_key + ": given together with its new name " + new_key + " in " +
                              where + "; keep only " + new_key);
}

std::string DeprecationWarning(const std::string& old_key, const std::string& new_key,
                               const std::string& where) {
  return where + ": " + old_key + " is deprecated, renamed " + new_key +
         " (the old name is read until the next release)";
}

Status UnknownKey(const std::string& key, const std::string& where,
                  const std::vector<std::string>& known_keys) {
  std::string msg = key + ": unknown key in " + where;
  const std::string closest = ClosestKey(key, known_keys);
  if (!closest.empty()) msg += " (did you mean " + closest + "?)";
  return Status::InvalidInput(msg);
}

std::string DumpVisitor::Text() const {
  size_t column = 0;
  for (const auto& l : lines_)
    if (!l.second.empty()) column = std::max(column, l.first.size());
  column = std::min<size_t>(column, 48);
  std::string out;
  for (const auto& l : lines_) {
    out += l.first;
    if (!l.second.empty())
      out += std::string(column > l.first.size() ? column - l.first.size() : 0, ' ') + "  # " +
             l.second;
    out += "\n";
  }
  return out;
}

std::string DumpVisitor::FormatDouble(double x) {
  if (std::isnan(x)) return ".nan";
  if (std::isinf(x)) return x > 0 ? ".inf" : "-.inf";
  char buf[400];
  int precision = 1;  // fewest significant digits that read back exactly
  for (; precision < 17; ++precision) {
    std::snprintf(buf, sizeof(buf), "%.*g", precision, x);
    if (std::strtod(buf, nullptr) == x) break;
  }
  std::snprintf(buf, sizeof(buf), "%.*g", precision, x);
  const double magnitude = std::fabs(x);
  if (std::strchr(buf, 'e') != nullptr && magnitude >= 1.0 && magnitude < 1e16) {
    // %g writes 100 as 1e+02; plain digits read better for moderate values.
    const int decimals =
        std::max(0, precision - 1 - static_cast<int>(std::floor(std::log10(magnitude))));
    std::snprintf(buf, sizeof(buf), "%.*f", decimals, x);
  }
  std::string s = buf;
  // Keep a '.' in the mantissa so that YAML 1.1 readers (PyYAML) see a float.
  const size_t e = s.find('e');
  const std::string mantissa = s.substr(0, e);
  if (mantissa.find('.') == std::string::npos)
    s = mantissa + ".0" + (e == std::string::npos ? "" : s.substr(e));
  return s;
}

std::string DumpVisitor::FormatString(const std::string& s) {
  if (IsPlainSafe(s)) return s;
  std::string out = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof(buf), "\\x%02x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

std::string DumpVisitor::Comment(const Spec& spec) {
  std::string c = spec.unit.empty() ? "" : "[" + spec.unit + "]";
  if (!spec.help.empty()) c += (c.empty() ? "" : " ") + spec.help;
  if (!spec.choices.empty()) {
    std::string list;
    for (const auto& choice : spec.choices) list += (list.empty() ? "" : " | ") + choice;
    c += (c.empty() ? "" : "; ") + list;
  }
  return c;
}

}  // namespace config_detail

const YamlNode* YamlNode::Find(const std::string& key) const {
  for (size_t i = 0; i < keys.size(); ++i)
    if (keys[i] == key) return &items[i];
  return nullptr;
}

StatusOr<YamlNode> ReadYamlFile(const std::string& path) {
  return config_detail::ParseYamlFile(path);
}

std::string YamlWhere(const std::string& source, int line) {
  return config_detail::Where(source, line);
}

Status AttributeToSources(const Status& status, const std::vector<std::string>& leaf_keys,
                          const ConfigSources& sources) {
  if (status.ok()) return status;
  const std::string& msg = status.message();
  std::vector<std::pair<size_t, std::string>> mentioned;  // position, key
  for (const auto& k : leaf_keys) {
    const size_t pos = config_detail::FindKey(msg, k);
    if (pos != std::string::npos) mentioned.emplace_back(pos, k);
  }
  std::sort(mentioned.begin(), mentioned.end());
  std::string first_source;
  for (const auto& m : mentioned) {
    auto it = sources.find(m.second);
    if (it != sources.end()) {
      first_source = it->second;
      break;
    }
  }
  if (first_source.empty()) return status;
  std::string out = first_source + ": " + msg;
  if (mentioned.size() > 1) {
    std::string list;
    for (const auto& m : mentioned) {
      auto it = sources.find(m.second);
      list += (list.empty() ? "" : ", ") + m.second + " from " +
              (it == sources.end() ? std::string("built-in default") : it->second);
    }
    out += " (" + list + ")";
  }
  return Status::InvalidInput(out);
}

StatusOr<Configuration> LoadConfig(const std::vector<std::string>& config_files,
                                     const std::vector<std::string>& set_overrides,
                                     std::vector<std::string>* warnings) {
  return LoadOptions<Configuration>(config_files, set_overrides, nullptr, warnings);
}

}  // namespace rvlio

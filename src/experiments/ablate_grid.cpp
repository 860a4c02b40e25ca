#include "rvlio/experiments/ablate_grid.h"


#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <vector>
#include <sstream>

#include "rvlio/common/fnv1a.h"
#include "rvlio/common/number_text.h"
#include "rvlio/common/text.h"
#include "rvlio/config/config.h"
#include "rvlio/config/yaml_tree.h"
#include "rvlio/outputs/summary_json.h"
#include "rvlio/sim/presets.h"

namespace rvlio::experiments::ablate {
namespace {

namespace fs = std::filesystem;
using Node = YamlNode;

constexpr size_t kMaxRangeValues = 10000;

// Where grid errors point: "grid.yaml:LINE: PATH: MESSAGE".
class GridContext {
 public:
  explicit GridContext(std::string grid_path)
      : path_(std::move(grid_path)), base_(fs::path(path_).parent_path()) {}
  Status Error(const Node& n, const std::string& key, const std::string& msg) const {
    return Status::InvalidInput(YamlWhere(path_, n.line) + ": " + key + ": " + msg);
  }
  // A path of the grid, relative to the grid file's folder.
  std::string Resolve(const std::string& p) const {
    const fs::path path(p);
    return (path.is_absolute() || base_.empty() ? path : base_ / path).lexically_normal().string();
  }

 private:
  std::string path_;
  fs::path base_;
};

const Node* Find(const Node& map, const std::string& key) { return map.Find(key); }

// Every key of `map` must be one of `known`.
Status CheckKeys(const GridContext& g, const Node& map, const std::string& path,
                 const std::vector<std::string>& known) {
  for (size_t i = 0; i < map.keys.size(); ++i)
    if (std::find(known.begin(), known.end(), map.keys[i]) == known.end()) {
      Node at;
      at.line = map.key_lines[i];
      return g.Error(at, (path.empty() ? "" : path + ".") + map.keys[i],
                     "unknown key (expected one of: " + Join(known, ", ") + ")");
    }
  return Status::Ok();
}

Status ExpectMap(const GridContext& g, const Node& n, const std::string& key) {
  return n.kind == Node::Kind::kMap ? Status::Ok() : g.Error(n, key, "expected a mapping");
}

// A scalar or a flow sequence of scalars as `--set` value text.
StatusOr<std::string> ValueText(const GridContext& g, const Node& n, const std::string& key) {
  if (n.kind == Node::Kind::kScalar) return n.scalar;
  if (n.kind == Node::Kind::kSequence) {
    std::vector<std::string> parts;
    for (const Node& item : n.items) {
      if (item.kind != Node::Kind::kScalar) return g.Error(n, key, "expected a list of scalars");
      parts.push_back(item.scalar);
    }
    return "[" + Join(parts, ",") + "]";
  }
  return g.Error(n, key, "expected a value (scalar or list)");
}

// {a: {b: 1}, c.d: 2} -> ["a.b=1", "c.d=2"], in file order. `skip` names a
// top-level key handled by the caller (a variant's `config`).
Status FlattenOverrides(const GridContext& g, const Node& map, const std::string& prefix,
                        const std::string& where, const std::string& skip,
                        std::vector<std::string>* out) {
  for (size_t i = 0; i < map.keys.size(); ++i) {
    const std::string key = prefix.empty() ? map.keys[i] : prefix + "." + map.keys[i];
    if (prefix.empty() && map.keys[i] == skip) continue;
    const Node& v = map.items[i];
    if (v.kind == Node::Kind::kMap) {
      if (Status s = FlattenOverrides(g, v, key, where, "", out); !s.ok()) return s;
      continue;
    }
    StatusOr<std::string> text = ValueText(g, v, where + "." + key);
    if (!text.ok()) return text.status();
    out->push_back(key + "=" + *text);
  }
  return Status::Ok();
}

Status ReadOverrides(const GridContext& g, const Node* n, const std::string& where,
                     std::vector<std::string>* out) {
  if (n == nullptr || n->kind == Node::Kind::kNull) return Status::Ok();
  if (Status s = ExpectMap(g, *n, where); !s.ok()) return s;
  return FlattenOverrides(g, *n, "", where, "", out);
}

// `config: file` or `config: [files]`; each must exist.
Status ReadConfigFiles(const GridContext& g, const Node* n, const std::string& where,
                       std::vector<std::string>* out) {
  if (n == nullptr || n->kind == Node::Kind::kNull) return Status::Ok();
  std::vector<const Node*> items;
  if (n->kind == Node::Kind::kScalar)
    items.push_back(n);
  else if (n->kind == Node::Kind::kSequence)
    for (const Node& i : n->items) items.push_back(&i);
  else
    return g.Error(*n, where, "expected a file or a list of files");
  for (const Node* i : items) {
    if (i->kind != Node::Kind::kScalar) return g.Error(*n, where, "expected file names");
    const std::string path = g.Resolve(i->scalar);
    if (!fs::is_regular_file(path)) return g.Error(*i, where, "file not found: " + path);
    out->push_back(path);
  }
  return Status::Ok();
}

std::string FormatValue(double v, bool integer) {
  char buf[48];
  if (integer)
    std::snprintf(buf, sizeof(buf), "%lld", static_cast<long long>(std::llround(v)));
  else
    std::snprintf(buf, sizeof(buf), "%.12g", v);
  std::string s = buf;
  return s == "-0" ? "0" : s;
}

// A list of values or a {from, to, step} range.
StatusOr<std::vector<std::string>> ReadValues(const GridContext& g, const Node& n,
                                              const std::string& where) {
  if (n.kind == Node::Kind::kMap) {
    if (Status s = CheckKeys(g, n, where, {"from", "to", "step"}); !s.ok()) return s;
    const Node *from = Find(n, "from"), *to = Find(n, "to"), *step = Find(n, "step");
    for (auto [name, node] :
         {std::pair<const char*, const Node*>{"from", from}, {"to", to}, {"step", step}})
      if (node == nullptr || node->kind != Node::Kind::kScalar)
        return g.Error(n, where + "." + name, "a range needs from, to and step (numbers)");
    StatusOr<std::vector<std::string>> values = ExpandRange(from->scalar, to->scalar, step->scalar);
    if (!values.ok()) return g.Error(n, where, values.status().message());
    return values;
  }
  if (n.kind != Node::Kind::kSequence || n.items.empty())
    return g.Error(n, where, "expected a non-empty list of values or {from, to, step}");
  std::vector<std::string> values;
  for (const Node& item : n.items) {
    StatusOr<std::string> text = ValueText(g, item, where);
    if (!text.ok()) return text.status();
    values.push_back(*text);
  }
  return values;
}

// Recorded bags are identified by path, size and modification time (hashing
// gigabytes of bag on every plan would be slow); a ROS 2 bag folder by those
// of each of its files.
std::string FileIdentity(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return path;
  return fs::absolute(path).lexically_normal().string() + "|" + std::to_string(st.st_size) + "|" +
         std::to_string(static_cast<long long>(st.st_mtime));
}

std::string BagIdentity(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return FileIdentity(path);
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(path, ec)) {
    if (e.is_regular_file(ec)) files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  std::string id = FileIdentity(path);
  for (const std::string& f : files) id += ";" + FileIdentity(f);
  return id;
}

std::string Sanitize(const std::string& s) {
  std::string out;
  for (char c : s)
    out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.') ? c : '_';
  return out.empty() ? "_" : out;
}

struct Variant {
  std::string name;
  std::vector<std::string> config_files, overrides;
};

// The part of a sequence that is the same for all its seeds.
struct Sequence {
  std::string name;
  bool simulated = false;
  std::string bag, gt;  // recorded
  std::string preset;
  std::string duration;  // simulated; "" = the preset's
  std::vector<std::string> sim_overrides;
  std::vector<int64_t> seeds;
  std::vector<std::string> config_files, overrides;
  std::string ref_map;  // reference cloud, or ""
};

struct Grid {
  std::vector<std::string> config_files, overrides;
  std::vector<Sequence> sequences;
  std::vector<Variant> variants;
  std::vector<std::pair<std::string, std::vector<std::string>>> parameters;
  JobResources resources;
};

Status ReadSeeds(const GridContext& g, const Node* n, const std::string& where,
                 std::vector<int64_t>* seeds) {
  if (n == nullptr) {
    seeds->push_back(1);
    return Status::Ok();
  }
  StatusOr<std::vector<std::string>> values = ReadValues(g, *n, where);
  if (!values.ok()) return values.status();
  for (const std::string& v : *values) {
    int64_t seed = -1;
    if (!ParseInteger(v, &seed) || seed < 0)
      return g.Error(*n, where, "'" + v + "' is not a non-negative integer seed");
    seeds->push_back(seed);
  }
  return Status::Ok();
}

// Checks the simulator options now, so a typo stops the grid, not every cell.
Status CheckSimulation(const GridContext& g, const Node& n, const Sequence& seq,
                       const std::string& where) {
  StatusOr<SimOptions> options = sim::PresetOptions(seq.preset);
  if (!options.ok()) return g.Error(n, where + ".preset", options.status().message());
  if (!seq.duration.empty() && !ParseNumber(seq.duration, &options->duration))
    return g.Error(n, where + ".duration", "'" + seq.duration + "' is not a number of seconds");
  for (const std::string& o : seq.sim_overrides)
    if (Status s = ApplyOverride(*options, o); !s.ok())
      return g.Error(n, where + ".set", s.message());
  if (Status s = options->Validate(); !s.ok()) return g.Error(n, where, s.message());
  return Status::Ok();
}

Status ReadSimulation(const GridContext& g, const Node& n, const std::string& where,
                      Sequence* seq) {
  if (Status s = ExpectMap(g, n, where); !s.ok()) return s;
  if (Status s = CheckKeys(g, n, where, {"preset", "duration", "set"}); !s.ok()) return s;
  seq->simulated = true;
  seq->preset = "tunnel";
  if (const Node* p = Find(n, "preset")) {
    if (p->kind != Node::Kind::kScalar) return g.Error(*p, where + ".preset", "expected a name");
    seq->preset = p->scalar;
  }
  if (const Node* d = Find(n, "duration")) {
    if (d->kind != Node::Kind::kScalar) return g.Error(*d, where + ".duration", "expected seconds");
    seq->duration = d->scalar;
  }
  if (Status s = ReadOverrides(g, Find(n, "set"), where + ".set", &seq->sim_overrides); !s.ok())
    return s;
  return CheckSimulation(g, n, *seq, where);
}

Status ReadRecorded(const GridContext& g, const Node& n, const std::string& where, Sequence* seq) {
  const Node* bag = Find(n, "bag");
  if (bag == nullptr || bag->kind != Node::Kind::kScalar)
    return g.Error(n, where, "needs `bag: FILE` or `simulate: {...}`");
  seq->bag = g.Resolve(bag->scalar);
  // A file (ROS1 .bag, .db3, .mcap) or a ROS 2 bag folder.
  if (!fs::is_regular_file(seq->bag) && !fs::is_directory(seq->bag))
    return g.Error(*bag, where + ".bag", "file not found: " + seq->bag);
  if (const Node* gt = Find(n, "gt")) {
    if (gt->kind != Node::Kind::kScalar) return g.Error(*gt, where + ".gt", "expected a file");
    seq->gt = g.Resolve(gt->scalar);
    if (!fs::is_regular_file(seq->gt))
      return g.Error(*gt, where + ".gt", "file not found: " + seq->gt);
  }
  if (Find(n, "seeds") != nullptr)
    return g.Error(*Find(n, "seeds"), where + ".seeds", "only simulated sequences have seeds");
  return Status::Ok();
}

Status ReadSequence(const GridContext& g, const Node& n, const std::string& where, Sequence* seq) {
  if (Status s = ExpectMap(g, n, where); !s.ok()) return s;
  if (Status s =
          CheckKeys(g, n, where,
                    {"name", "bag", "gt", "simulate", "seeds", "config", "set", "ref_map"});
      !s.ok())
    return s;
  const Node* name = Find(n, "name");
  if (name == nullptr || name->kind != Node::Kind::kScalar || name->scalar.empty())
    return g.Error(n, where + ".name", "every sequence needs a name");
  seq->name = name->scalar;
  if (const Node* sim = Find(n, "simulate")) {
    if (Find(n, "bag") != nullptr)
      return g.Error(*sim, where, "give either bag or simulate, not both");
    if (Status s = ReadSimulation(g, *sim, where + ".simulate", seq); !s.ok()) return s;
    if (Status s = ReadSeeds(g, Find(n, "seeds"), where + ".seeds", &seq->seeds); !s.ok()) return s;
  } else if (Status s = ReadRecorded(g, n, where, seq); !s.ok()) {
    return s;
  }
  if (const Node* ref = Find(n, "ref_map")) {
    if (ref->kind != Node::Kind::kScalar)
      return g.Error(*ref, where + ".ref_map", "expected a PCD or PLY file");
    seq->ref_map = g.Resolve(ref->scalar);
    if (!fs::is_regular_file(seq->ref_map))
      return g.Error(*ref, where + ".ref_map", "file not found: " + seq->ref_map);
  }
  if (Status s = ReadConfigFiles(g, Find(n, "config"), where + ".config", &seq->config_files);
      !s.ok())
    return s;
  return ReadOverrides(g, Find(n, "set"), where + ".set", &seq->overrides);
}

Status ReadVariants(const GridContext& g, const Node* n, std::vector<Variant>* variants) {
  if (n == nullptr || n->kind == Node::Kind::kNull) {
    variants->push_back({"default", {}, {}});
    return Status::Ok();
  }
  if (Status s = ExpectMap(g, *n, "variants"); !s.ok()) return s;
  if (n->keys.empty()) return g.Error(*n, "variants", "expected at least one variant");
  for (size_t i = 0; i < n->keys.size(); ++i) {
    const std::string where = "variants." + n->keys[i];
    const Node& v = n->items[i];
    Variant variant{n->keys[i], {}, {}};
    if (v.kind != Node::Kind::kNull) {
      if (Status s = ExpectMap(g, v, where); !s.ok()) return s;
      if (Status s =
              ReadConfigFiles(g, Find(v, "config"), where + ".config", &variant.config_files);
          !s.ok())
        return s;
      if (Status s = FlattenOverrides(g, v, "", where, "config", &variant.overrides); !s.ok())
        return s;
    }
    variants->push_back(std::move(variant));
  }
  return Status::Ok();
}

Status ReadParameters(const GridContext& g, const Node* n, Grid* grid) {
  if (n == nullptr || n->kind == Node::Kind::kNull) return Status::Ok();
  if (Status s = ExpectMap(g, *n, "parameters"); !s.ok()) return s;
  for (size_t i = 0; i < n->keys.size(); ++i) {
    StatusOr<std::vector<std::string>> values =
        ReadValues(g, n->items[i], "parameters." + n->keys[i]);
    if (!values.ok()) return values.status();
    grid->parameters.emplace_back(n->keys[i], std::move(values).value());
  }
  return Status::Ok();
}

// `resources: {cpus, mem_mb, runtime}`: whole numbers, each optional.
Status ReadResources(const GridContext& g, const Node* n, JobResources* r) {
  if (n == nullptr || n->kind == Node::Kind::kNull) return Status::Ok();
  if (Status s = ExpectMap(g, *n, "resources"); !s.ok()) return s;
  if (Status s = CheckKeys(g, *n, "resources", {"cpus", "mem_mb", "runtime"}); !s.ok()) return s;
  const struct {
    const char* key;
    const char* unit;
    long long max;
    int* value;
  } fields[] = {{"cpus", "CPUs", 1024, &r->cpus},
                {"mem_mb", "MB", 100000000, &r->mem_mb},
                {"runtime", "minutes", 525600, &r->runtime_min}};
  for (const auto& f : fields) {
    const Node* v = Find(*n, f.key);
    if (v == nullptr) continue;
    const std::string where = std::string("resources.") + f.key;
    int64_t x = 0;
    if (v->kind != Node::Kind::kScalar || !ParseInteger(v->scalar, &x)) x = 0;
    if (x < 1 || x > f.max)
      return g.Error(*v, where,
                     "'" + v->scalar + "' is not a whole number of " + f.unit + " in [1, " +
                         std::to_string(f.max) + "]");
    *f.value = static_cast<int>(x);
  }
  return Status::Ok();
}

StatusOr<Grid> ReadGrid(const GridContext& g, const Node& root) {
  Grid grid;
  if (root.kind != Node::Kind::kMap) return g.Error(root, "sequences", "the grid file is empty");
  if (Status s = CheckKeys(g, root, "",
                           {"sequences", "variants", "parameters", "config", "set", "resources"});
      !s.ok())
    return s;
  const Node* seqs = Find(root, "sequences");
  if (seqs == nullptr || seqs->kind != Node::Kind::kSequence || seqs->items.empty())
    return g.Error(seqs ? *seqs : root, "sequences", "expected a non-empty list of sequences");
  for (size_t i = 0; i < seqs->items.size(); ++i) {
    Sequence seq;
    if (Status s = ReadSequence(g, seqs->items[i], "sequences[" + std::to_string(i) + "]", &seq);
        !s.ok())
      return s;
    for (const Sequence& other : grid.sequences)
      if (other.name == seq.name)
        return g.Error(seqs->items[i], "sequences[" + std::to_string(i) + "].name",
                       "duplicate sequence name '" + seq.name + "'");
    grid.sequences.push_back(std::move(seq));
  }
  if (Status s = ReadVariants(g, Find(root, "variants"), &grid.variants); !s.ok()) return s;
  if (Status s = ReadParameters(g, Find(root, "parameters"), &grid); !s.ok()) return s;
  if (Status s = ReadConfigFiles(g, Find(root, "config"), "config", &grid.config_files); !s.ok())
    return s;
  if (Status s = ReadOverrides(g, Find(root, "set"), "set", &grid.overrides); !s.ok()) return s;
  if (Status s = ReadResources(g, Find(root, "resources"), &grid.resources); !s.ok()) return s;
  return grid;
}

// ---------------------------------------------------------------------------
// Expansion
// ---------------------------------------------------------------------------

DataItem MakeDataItem(const Sequence& seq, int64_t seed, const std::string& out_dir) {
  DataItem d;
  d.sequence = seq.name;
  d.seed = seed;
  const std::string stem = Sanitize(seq.name);
  std::vector<std::string> args = {"simulate", "--preset", seq.preset, "--seed",
                                   std::to_string(seed)};
  if (!seq.duration.empty()) args.insert(args.end(), {"--duration", seq.duration});
  for (const auto& o : seq.sim_overrides) args.insert(args.end(), {"--set", o});
  args.insert(args.end(), {"--name", stem});
  d.hash = Fnv1aHex(JsonText(nlohmann::json({{"format", 1}, {"simulate", args}}), -1));
  d.id = stem + "_s" + std::to_string(seed) + "_" + d.hash.substr(0, 10);
  d.dir = (fs::path(out_dir) / "data" / d.id).string();
  args.insert(args.end(), {"--out", d.dir});
  d.simulate_args = std::move(args);
  d.bag = d.dir + "/" + stem + ".bag";
  d.gt = d.dir + "/" + stem + "_gt.tum";
  d.sensor_config = d.dir + "/" + stem + ".yaml";
  return d;
}

// Every combination of the parameter values, first key slowest.
std::vector<std::vector<std::pair<std::string, std::string>>> ParameterProduct(const Grid& grid) {
  std::vector<std::vector<std::pair<std::string, std::string>>> combos(1);
  for (const auto& [key, values] : grid.parameters) {
    std::vector<std::vector<std::pair<std::string, std::string>>> next;
    for (const auto& c : combos)
      for (const auto& v : values) {
        next.push_back(c);
        next.back().emplace_back(key, v);
      }
    combos = std::move(next);
  }
  return combos;
}

// The configuration identity of a cell: data/bag, ground truth, config file
// contents (in order) and overrides (in order).
std::string CellHash(const Cell& c, const Plan& plan) {
  nlohmann::json files = nlohmann::json::array();
  for (const auto& f : c.config_files) {
    const bool generated = c.data_index >= 0 && f == plan.data[c.data_index].sensor_config;
    files.push_back(generated ? std::string("<sensor config of data>") : Fnv1aHex(ReadFileText(f)));
  }
  const nlohmann::json identity = {
      {"format", 1},
      {"data", c.data_index >= 0 ? plan.data[c.data_index].hash : BagIdentity(c.bag)},
      {"gt", c.gt.empty() || c.data_index >= 0 ? "" : Fnv1aHex(ReadFileText(c.gt))},
      {"config", files},
      {"set", c.overrides},
      {"eval", "se3,rpe1"}};
  nlohmann::json with_map = identity;
  if (!c.ref_map.empty()) with_map["ref_map"] = FileIdentity(c.ref_map);  // older hashes unchanged
  return Fnv1aHex(JsonText(with_map, -1));
}

// Checks the keys and values of a cell's configuration now (the sensor file
// of a simulated sequence does not exist yet and only holds sensor keys).
Status CheckCellConfig(const GridContext& g, const Cell& c, const Plan& plan) {
  std::vector<std::string> files;
  for (const auto& f : c.config_files)
    if (c.data_index < 0 || f != plan.data[c.data_index].sensor_config) files.push_back(f);
  StatusOr<Configuration> options = LoadConfig(files, c.overrides);
  if (options.ok()) return Status::Ok();
  return g.Error(Node(), "cell " + c.sequence + "/" + c.label, options.status().message());
}

void AddCells(const Grid& grid, const Sequence& seq, int data_index, Plan* plan) {
  const bool with_params = !grid.parameters.empty();
  for (const Variant& v : grid.variants)
    for (const auto& params : ParameterProduct(grid)) {
      Cell c;
      c.sequence = seq.name;
      c.variant = v.name;
      c.params = params;
      c.data_index = data_index;
      c.label = v.name;
      if (with_params) {
        std::vector<std::string> kv;
        for (const auto& [k, val] : params) kv.push_back(k + "=" + val);
        c.label += " " + Join(kv, ",");
      }
      if (data_index >= 0) {
        const DataItem& d = plan->data[data_index];
        c.has_seed = true;
        c.seed = d.seed;
        c.bag = d.bag;
        c.gt = d.gt;
      } else {
        c.bag = seq.bag;
        c.gt = seq.gt;
      }
      c.ref_map = seq.ref_map;
      c.config_files = grid.config_files;
      if (data_index >= 0) c.config_files.push_back(plan->data[data_index].sensor_config);
      for (const auto* list : {&seq.config_files, &v.config_files})
        c.config_files.insert(c.config_files.end(), list->begin(), list->end());
      for (const auto* list : {&grid.overrides, &seq.overrides, &v.overrides})
        c.overrides.insert(c.overrides.end(), list->begin(), list->end());
      for (const auto& [k, val] : params) c.overrides.push_back(k + "=" + val);
      c.hash = CellHash(c, *plan);
      c.id = Sanitize(seq.name) + "_" + Sanitize(v.name) +
             (c.has_seed ? "_s" + std::to_string(c.seed) : "") + "_" + c.hash.substr(0, 10);
      c.dir = (fs::path(plan->out_dir) / "cells" / c.id).string();
      plan->cells.push_back(std::move(c));
    }
}

}  // namespace

StatusOr<std::vector<std::string>> ExpandRange(const std::string& from_text,
                                               const std::string& to_text,
                                               const std::string& step_text) {
  double from = 0, to = 0, step = 0;
  if (!ParseNumber(from_text, &from) || !ParseNumber(to_text, &to) ||
      !ParseNumber(step_text, &step))
    return Status::InvalidInput("range from/to/step must be numbers");
  if (step == 0.0) return Status::InvalidInput("range step must not be 0");
  const double steps = (to - from) / step;
  if (steps < -1e-9)
    return Status::InvalidInput("empty range: from " + from_text + " does not reach to " + to_text +
                                " with step " + step_text);
  // The 1e-9 tolerance makes 0.1..0.5 step 0.1 end at 0.5 despite rounding.
  const double count = std::floor(steps + 1e-9) + 1.0;
  if (count > static_cast<double>(kMaxRangeValues))
    return Status::InvalidInput("range has more than " + std::to_string(kMaxRangeValues) +
                                " values");
  const bool integer =
      IsIntegerText(from_text) && IsIntegerText(to_text) && IsIntegerText(step_text);
  std::vector<std::string> values;
  for (size_t i = 0; i < static_cast<size_t>(count); ++i)
    values.push_back(FormatValue(from + static_cast<double>(i) * step, integer));
  return values;
}

std::vector<std::string> Cell::RunArgs() const {
  std::vector<std::string> a = {"run", "--bag", bag};
  for (const auto& f : config_files) a.insert(a.end(), {"--config", f});
  for (const auto& o : overrides) a.insert(a.end(), {"--set", o});
  a.insert(a.end(), {"--out", RunDir(), "--quiet"});
  return a;
}

std::vector<std::string> Cell::EvalArgs() const {
  if (gt.empty()) return {};
  return {"eval", "--gt", gt, "--est", RunDir() + "/trajectory.tum", "--json"};
}

bool Plan::HasRefMap() const {
  for (const Cell& c : cells)
    if (!c.ref_map.empty()) return true;
  return false;
}

bool Plan::HasSimulated() const {
  for (const Cell& c : cells)
    if (c.data_index >= 0) return true;
  return false;
}

// The number of cells the grid expands to (a double: the product of the
// ranges may exceed int64), and how it is made up.
double CountCells(const Grid& grid, std::string* how) {
  double data = 0.0, combos = 1.0;
  for (const Sequence& seq : grid.sequences) data += seq.simulated ? seq.seeds.size() : 1.0;
  for (const auto& p : grid.parameters) combos *= static_cast<double>(p.second.size());
  char text[160];
  std::snprintf(text, sizeof(text), "%.0f sequences x seeds, %zu variants, %.0f parameter combinations",
                data, grid.variants.size(), combos);
  *how = text;
  return data * static_cast<double>(grid.variants.size()) * combos;
}

StatusOr<Plan> LoadPlan(const std::string& grid_path, const std::string& out_dir,
                        int64_t max_cells) {
  const GridContext g(grid_path);
  StatusOr<Node> root = ReadYamlFile(grid_path);
  if (!root.ok()) {
    const std::string& m = root.status().message();
    return Status::InvalidInput(m.rfind(grid_path, 0) == 0 ? m : grid_path + ": " + m);
  }
  StatusOr<Grid> grid = ReadGrid(g, *root);
  if (!grid.ok()) return grid.status();
  std::string how;
  const double cells = CountCells(*grid, &how);
  if (cells > static_cast<double>(max_cells)) {
    char count[64];
    std::snprintf(count, sizeof(count), "%.6g", cells);
    return Status::InvalidInput(grid_path + ": the grid has " + count + " cells (" + how +
                                "), more than the limit of " + std::to_string(max_cells) +
                                "; --max-cells N allows more");
  }
  Plan plan;
  plan.grid_path = grid_path;
  plan.out_dir = out_dir;
  plan.resources = grid->resources;
  for (const auto& p : grid->parameters) plan.param_keys.push_back(p.first);
  for (const Sequence& seq : grid->sequences) {
    if (!seq.simulated) {
      AddCells(*grid, seq, -1, &plan);
      continue;
    }
    for (int64_t seed : seq.seeds) {
      plan.data.push_back(MakeDataItem(seq, seed, out_dir));
      AddCells(*grid, seq, static_cast<int>(plan.data.size()) - 1, &plan);
    }
  }
  std::map<std::string, const Cell*> seen;
  for (const Cell& c : plan.cells) {
    if (!seen.emplace(c.id, &c).second)
      return g.Error(*root, "cells",
                     "two cells resolve to the same configuration (" + c.id +
                         "): duplicate variants or parameter values?");
    if (Status s = CheckCellConfig(g, c, plan); !s.ok()) return s;
  }
  return plan;
}

std::string PlanJsonText(const Plan& plan) {
  nlohmann::json data = nlohmann::json::array(), cells = nlohmann::json::array();
  for (const DataItem& d : plan.data)
    data.push_back({{"id", d.id},
                    {"hash", d.hash},
                    {"sequence", d.sequence},
                    {"seed", d.seed},
                    {"dir", d.dir},
                    {"marker", d.Marker()},
                    {"simulate_argv", d.simulate_args},
                    {"bag", d.bag},
                    {"gt", d.gt},
                    {"config", d.sensor_config}});
  for (const Cell& c : plan.cells) {
    nlohmann::json params = nlohmann::json::object();
    for (const auto& [k, v] : c.params) params[k] = v;
    cells.push_back({{"id", c.id},
                     {"hash", c.hash},
                     {"sequence", c.sequence},
                     {"seed", c.has_seed ? nlohmann::json(c.seed) : nlohmann::json(nullptr)},
                     {"variant", c.variant},
                     {"params", params},
                     {"label", c.label},
                     {"dir", c.dir},
                     {"cell_json", c.CellJson()},
                     {"data", c.data_index >= 0 ? nlohmann::json(plan.data[c.data_index].id)
                                                : nlohmann::json(nullptr)},
                     {"run_argv", c.RunArgs()},
                     {"eval_argv", c.EvalArgs()},
                     {"ref_map", c.ref_map}});
  }
  const nlohmann::json j = {{"grid", plan.grid_path},
                            {"out", plan.out_dir},
                            {"param_keys", plan.param_keys},
                            {"resources",
                             {{"cpus", plan.resources.cpus},
                              {"mem_mb", plan.resources.mem_mb},
                              {"runtime", plan.resources.runtime_min}}},
                            {"data", data},
                            {"cells", cells}};
  return JsonText(j) + "\n";
}

}  // namespace rvlio::experiments::ablate

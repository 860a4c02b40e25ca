#pragma once
// YAML documents as a plain tree (YamlNode), free of yaml-cpp types: what the
// configuration loader (config.h) walks, and the public way for other files
// of the project (an ablation grid, rvlio/experiments/ablate_grid.h) to be
// read with the same parser, limits and error messages.
#include <string>
#include <vector>

#include "rvlio/common/status.h"

namespace rvlio {

// A parsed YAML document.
struct YamlNode {
  enum class Kind { kNull, kScalar, kSequence, kMap };
  Kind kind = Kind::kNull;
  std::string scalar;             // kScalar: the text as written (unquoted)
  std::vector<YamlNode> items;    // kSequence elements; kMap values
  std::vector<std::string> keys;  // kMap keys, parallel to items
  std::vector<int> key_lines;     // kMap: line of each key
  int line = 0;                   // 1-based line in the source, 0 if unknown (--set)
  // Root only: the document has more values than a configuration can (an
  // alias bomb, or a large section); the values past the limit are nulls.
  std::string over_budget;

  // The value of `key` in a kMap (nullptr when absent or not a map).
  const YamlNode* Find(const std::string& key) const;
};

// Reads a whole YAML file (top level a mapping or empty). InvalidInput naming
// the file, and the line for syntax errors and duplicate keys; a document
// with more values than the limit is refused.
StatusOr<YamlNode> ReadYamlFile(const std::string& path);

// "file.yaml:12", or just `source` when the line is unknown (0): the prefix of
// every message about a place in a YAML file.
std::string YamlWhere(const std::string& source, int line);

}  // namespace rvlio

#pragma once
#include <string>
#include <vector>

#include "common.h"
#include "rvlio/config/configuration.h"

namespace rvlio::python {

// rvlio.Config: the resolved options and what they were loaded from (the
// files and `set` overrides, as `rvlio run --config F --set K=V` takes them).
struct Config {
  Configuration options;
  std::vector<std::string> files;
  std::vector<std::string> overrides;  // "key=value"
};

void BindConfig(py::module_& m);

// A `set={...}` dict (or None) as `--set` arguments "key=value": bool ->
// true/false, numbers exactly, lists and tuples -> [a,b,c], str as is.
std::vector<std::string> Overrides(const py::handle& set);

// A `config` argument: an rvlio.Config, a YAML path (loaded alone) or None
// (the defaults, *storage as constructed). Returns the Config to use.
const Config& ConfigArg(const py::handle& config, Config* storage);

}  // namespace rvlio::python

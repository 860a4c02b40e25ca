// rvlio.Config: the odometry configuration of `rvlio run` (config/config.h).
#include "config_py.h"

#include <pybind11/stl.h>

#include "rvlio/config/config.h"
#include "rvlio/config/config_json.h"

namespace rvlio::python {
namespace {

// The text of one `--set` value: YAML scalar or flow sequence.
std::string OverrideText(const py::handle& value) {
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value) ||
      py::isinstance<py::array>(value)) {
    std::string text = "[";
    for (const py::handle item : py::iter(value))
      text += (text.size() > 1 ? "," : "") + OverrideText(item);
    return text + "]";
  }
  // int, float, numpy scalars: repr is the shortest text that reads back exactly.
  if (py::isinstance<py::int_>(value)) return py::str(value).cast<std::string>();
  return py::repr(py::float_(py::reinterpret_borrow<py::object>(value))).cast<std::string>();
}

}  // namespace

std::vector<std::string> Overrides(const py::handle& set) {
  std::vector<std::string> assignments;
  if (set.is_none()) return assignments;
  if (!py::isinstance<py::dict>(set))
    throw py::type_error("set must be a dict of 'section.key': value");
  for (const auto& [key, value] : py::reinterpret_borrow<py::dict>(set))
    assignments.push_back(py::str(key).cast<std::string>() + "=" + OverrideText(value));
  return assignments;
}

namespace {

Config Load(const py::args& files, const py::object& set) {
  Config c;
  for (const py::handle f : files) {
    c.files.push_back(PathText(f));
    RequireExisting(c.files.back(), "configuration file");
  }
  c.overrides = Overrides(set);
  std::vector<std::string> warnings;
  c.options = Take(LoadConfig(c.files, c.overrides, &warnings));
  // Deprecated option names (config.h): one FutureWarning each, as the CLI
  // prints one warning line each.
  for (const std::string& w : warnings)
    if (PyErr_WarnEx(PyExc_FutureWarning, w.c_str(), 1) != 0) throw py::error_already_set();
  return c;
}

}  // namespace

void BindConfig(py::module_& m) {
  py::class_<Config>(m, "Config",
                     "The odometry configuration (`rvlio run --config ... --set ...`): built-in "
                     "defaults, then each file, then each override, then validation.")
      .def(py::init<>(), "The built-in defaults.")
      .def_static("load", &Load,
                  "Config.load(*files, set={'rv.enabled': False}): YAML files in order (later "
                  "win), then the overrides. ValueError with the command-line tool's message "
                  "for an unknown key or a bad value; FileNotFoundError for a missing file.",
                  py::kw_only(), py::arg("set") = py::none())
      .def("to_dict", [](const Config& c) { return ToPython(ToJson(c.options)); },
           "Every key as nested dicts (summary.json's \"config\").")
      .def("dump", [](const Config& c) { return DumpYaml(c.options); },
           "The resolved configuration as YAML with units and help (rvlio config --dump).")
      .def_readonly("files", &Config::files)
      .def_readonly("overrides", &Config::overrides, "the `set` entries as 'key=value' texts")
      .def_property_readonly("backend", [](const Config& c) { return std::string(EnumName(c.options.backend)); })
      .def("__repr__", [](const Config& c) {
        return "rvlio.Config(backend='" + std::string(EnumName(c.options.backend)) + "', files=" +
               py::repr(py::cast(c.files)).cast<std::string>() + ", overrides=" +
               py::repr(py::cast(c.overrides)).cast<std::string>() + ")";
      });
}

const Config& ConfigArg(const py::handle& config, Config* storage) {
  if (config.is_none()) return *storage;
  if (py::isinstance<Config>(config)) return config.cast<const Config&>();
  if (py::isinstance<py::str>(config) || py::hasattr(config, "__fspath__")) {
    *storage = Load(py::make_tuple(config), py::none());
    return *storage;
  }
  throw py::type_error("config must be an rvlio.Config, a YAML path or None");
}

}  // namespace rvlio::python

#include "cli.h"

#include "rvlio/experiments/compare.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <iostream>

namespace rvlio::cli {

std::string Args::Get(const std::string& name, const std::string& fallback) const {
  auto it = values_.find(name);
  return (it == values_.end() || it->second.empty()) ? fallback : it->second.back();
}

const std::vector<std::string>& Args::GetAll(const std::string& name) const {
  static const std::vector<std::string> kEmpty;
  auto it = values_.find(name);
  return it == values_.end() ? kEmpty : it->second;
}

void PrintUsage(const CommandSpec& spec) {
  std::cout << "usage: rvlio " << spec.name;
  for (const auto& o : spec.options) {
    std::string item = "--" + o.name + (o.value.empty() ? "" : " " + o.value);
    if (o.repeatable) item += " ...";
    std::cout << " " << (o.required ? item : "[" + item + "]");
  }
  std::cout << "\n\n" << spec.summary << "\n\noptions:\n";
  for (const auto& o : spec.options) {
    std::string left = "--" + o.name + (o.value.empty() ? "" : " " + o.value);
    std::cout << "  " << left;
    for (size_t i = left.size(); i < 24; ++i) std::cout << ' ';
    std::cout << " " << o.help << (o.repeatable ? " (repeatable)" : "") << "\n";
  }
  std::cout << "  --help                   this text\n";
}

int Fail(const std::string& command, const std::string& message, int exit_code) {
  std::fprintf(stderr, "rvlio %s: error: %s\n", command.c_str(), message.c_str());
  return exit_code;
}

int ExitCode(StatusCode code) { return experiments::ExitStatus(code); }

int Fail(const std::string& command, const Status& status) {
  return Fail(command, status.message(), ExitCode(status.code()));
}

ProgressLine::ProgressLine(bool enabled) : enabled_(enabled && isatty(STDERR_FILENO)) {}

ProgressLine::~ProgressLine() {
  if (printed_) std::fprintf(stderr, "\n");
}

bool ProgressLine::Due(double wall_s) const {
  return enabled_ && wall_s >= 3.0 && wall_s - last_print_s_ >= 0.5;
}

void ProgressLine::Update(double wall_s, double fraction, const std::string& what) {
  if (!Due(wall_s)) return;
  last_print_s_ = wall_s;
  const double done = std::clamp(fraction, 0.0, 1.0);
  const double eta_s = done > 0.01 ? wall_s * (1.0 - done) / done : 0.0;
  std::fprintf(stderr, "\r  %s  %3.0f%%  ETA %.0f s   ", what.c_str(), 100.0 * done, eta_s);
  printed_ = true;
}

int Parse(const CommandSpec& spec, int argc, char** argv, int first, Args* out) {
  const OptionSpec* list = nullptr;  // the repeatable option whose values may follow
  for (int i = first; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      PrintUsage(spec);
      return -1;
    }
    if (arg.rfind("--", 0) != 0) {
      // A repeatable option takes a list: `--chunks A B C` is `--chunks A --chunks B --chunks C`
      // (the usage line shows it as `--chunks DIR ...`).
      if (list == nullptr) return Fail(spec.name, "unexpected argument '" + arg + "' (see --help)");
      if (arg.empty()) return Fail(spec.name, "option --" + list->name + " has an empty value");
      out->values_[list->name].push_back(arg);
      continue;
    }
    std::string name = arg.substr(2), value;
    bool inline_value = false;
    if (auto eq = name.find('='); eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
      inline_value = true;
    }
    const OptionSpec* opt = nullptr;
    for (const auto& o : spec.options)
      if (o.name == name) opt = &o;
    if (!opt) return Fail(spec.name, "unknown option --" + name + " (see --help)");
    if (!opt->value.empty() && !inline_value) {
      if (i + 1 >= argc) return Fail(spec.name, "option --" + name + " needs a value " + opt->value);
      value = argv[++i];
    } else if (opt->value.empty() && inline_value) {
      return Fail(spec.name, "option --" + name + " takes no value");
    }
    // An empty value is never meaningful and would reach the library as "not
    // given" (an empty output folder means "write nothing" to the API).
    if (!opt->value.empty() && value.empty())
      return Fail(spec.name, "option --" + name + " has an empty value");
    auto& slot = out->values_[name];
    if (!opt->repeatable && !slot.empty())
      return Fail(spec.name, "option --" + name + " given more than once");
    slot.push_back(value);
    list = opt->repeatable && !opt->value.empty() ? opt : nullptr;
  }
  for (const auto& o : spec.options)
    if (o.required && !out->Has(o.name)) return Fail(spec.name, "missing required option --" + o.name);
  return 0;
}

bool ParseWholeNumber(const std::string& text, long long min, long long max, long long* value) {
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno != 0 || v < min || v > max) return false;
  *value = v;
  return true;
}

}  // namespace rvlio::cli

#pragma once
// Minimal argument parsing for the rvlio subcommands: `--name value`,
// `--name=value`, repeatable options (which also take a list: `--chunks A B`)
// and boolean flags; an empty value is refused. Parsing errors are
// bad input (exit 2) with a one-line message.
#include <map>
#include <string>
#include <vector>

#include "rvlio/common/status.h"

namespace rvlio::cli {

struct OptionSpec {
  std::string name;   // without the leading dashes
  std::string value;  // value name shown in the usage line, empty for a flag
  std::string help;
  bool required = false;
  bool repeatable = false;
};

struct CommandSpec {
  std::string name;
  std::string summary;
  std::vector<OptionSpec> options;
};

class Args {
 public:
  bool Has(const std::string& name) const { return values_.count(name) > 0; }
  std::string Get(const std::string& name, const std::string& fallback = "") const;
  const std::vector<std::string>& GetAll(const std::string& name) const;
  std::map<std::string, std::vector<std::string>> values_;
};

// Parses argv[first..argc). Returns 0 and fills `out` on success; on --help
// prints the usage to stdout and returns -1; on a parsing error prints one
// line to stderr and returns 2.
int Parse(const CommandSpec& spec, int argc, char** argv, int first, Args* out);
void PrintUsage(const CommandSpec& spec);

// The whole number written in `text` (decimal, nothing else) when it lies in
// [min, max]; false otherwise, `value` untouched.
bool ParseWholeNumber(const std::string& text, long long min, long long max, long long* value);

// One-line error on stderr in the contract's form: "rvlio CMD: error: MSG".
int Fail(const std::string& command, const std::string& message, int exit_code = 2);

// The command-line contract's exit status for a library error
// (experiments::ExitStatus, the one place that maps them): 2 bad input or an output that cannot be written, 1 internal failure (divergence,
// 3, and signals, 130 / 143, are not Status errors: see divergence_cli.h, interrupt.h).
int ExitCode(StatusCode code);
// Fail with the status's message and ExitCode(status.code()).
int Fail(const std::string& command, const Status& status);

// A progress line on stderr for long work, only when stderr is a terminal:
// from 3 s on, at most every 0.5 s, "  WHAT  NN%  ETA S s", rewritten in
// place; the destructor ends the line. `fraction` is the share of the work
// asked for (0..1).
class ProgressLine {
 public:
  explicit ProgressLine(bool enabled);
  ~ProgressLine();
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;
  // True when the line is printed now (the caller may skip building `what`).
  bool Due(double wall_s) const;
  void Update(double wall_s, double fraction, const std::string& what);

 private:
  bool enabled_;
  double last_print_s_ = 0.0;
  bool printed_ = false;
};

}  // namespace rvlio::cli

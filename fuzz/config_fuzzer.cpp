// libFuzzer target: the configuration loader of `rvlio run --config F --set
// k=v` (config/config.h LoadOptions<Configuration>: defaults, YAML, overrides,
// Validate, source attribution) on fuzzed YAML text and override strings.
// Only ParseYamlFile's reading of the file is replaced by the text itself
// (ApplyYamlText is ApplyYamlFile after the read).
//
// Input layout (FuzzedDataProvider; fuzz/make_seeds.py writes the same): the
// override count (0..4) is the LAST byte; the overrides are strings at the
// FRONT (ConsumeRandomLengthString: "\\" escapes a backslash, "\\" + another
// character ends the string), and the YAML text is whatever remains.
//
// Invariants: no crash, no exception; every failure is InvalidInput with a
// message; a configuration that loads validates, and its DumpYaml applied to
// the defaults loads, validates and dumps identically (the documented round
// trip), and ToJson of it serializes.
#include <fuzzer/FuzzedDataProvider.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "rvlio/config/config.h"
#include "rvlio/config/config_json.h"

namespace {

using rvlio::Configuration;
using rvlio::Status;

[[noreturn]] void Fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "config fuzzer invariant violated: %s\n%s\n", what, detail.c_str());
  std::abort();
}

void RequireInvalidInput(const Status& s) {
  if (s.code() != rvlio::StatusCode::kInvalidInput || s.message().empty())
    Fail("a failure is not InvalidInput with a message", s.message());
}

// LoadOptions<Configuration> with the file replaced by its text.
Status Load(const std::string& yaml, const std::vector<std::string>& overrides,
            Configuration* options) {
  rvlio::ConfigSources sources;
  Status s = rvlio::ApplyYamlText(*options, yaml, "fuzz.yaml", &sources);
  if (!s.ok()) return s;
  for (const auto& o : overrides) {
    s = rvlio::ApplyOverride(*options, o, &sources);
    if (!s.ok()) return s;
  }
  s = options->Validate();
  if (!s.ok()) return rvlio::AttributeToSources(s, rvlio::ListKeys(*options), sources);
  return Status::Ok();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider fdp(data, size);
  const int n_overrides = fdp.ConsumeIntegralInRange<int>(0, 4);
  std::vector<std::string> overrides;
  for (int i = 0; i < n_overrides; ++i) overrides.push_back(fdp.ConsumeRandomLengthString(256));
  const std::string yaml = fdp.ConsumeRemainingBytesAsString();

  Configuration options;
  const Status s = Load(yaml, overrides, &options);
#ifdef RVLIO_FUZZ_VERBOSE  // seed checks: what an input loads to
  std::fprintf(stderr, "%zu overrides: %s\n", overrides.size(),
               s.ok() ? "ok" : s.message().c_str());
#endif
  if (!s.ok()) {
    RequireInvalidInput(s);
    return 0;
  }
  if (!options.Validate().ok()) Fail("a loaded configuration does not validate", yaml);

  const std::string dumped = rvlio::DumpYaml(options);
  Configuration restored;
  const Status r = Load(dumped, {}, &restored);
  if (!r.ok()) Fail("DumpYaml output does not load", r.message() + "\n" + dumped);
  if (rvlio::DumpYaml(restored) != dumped) Fail("DumpYaml round trip changed a value", dumped);
  (void)rvlio::ToJson(options).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  return 0;
}

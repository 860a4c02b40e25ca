#pragma once
// Option lists shared by several subcommands.
#include "cli.h"

namespace rvlio::cli {

inline OptionSpec ConfigOption() {
  return {"config", "FILE", "YAML configuration; later files override earlier ones", false, true};
}
inline OptionSpec AllowDivergenceOption() {
  return {"allow-divergence", "",
          "exit 0 even when the divergence monitor fired (the warnings and summary.json still "
          "say so; without it such a run exits 3)"};
}
inline OptionSpec SetOption() {
  return {"set", "KEY=VALUE", "override one key, e.g. rv.enabled=false (applied last)", false, true};
}

}  // namespace rvlio::cli

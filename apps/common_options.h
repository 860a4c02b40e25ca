#pragma once
// Option lists shared by several subcommands.
#include "cli.h"

namespace rvlio::cli {

inline OptionSpec ConfigOption() {
  return {"config", "FILE", "YAML configuration; later files override earlier ones", false, true};
}
inline OptionSpec SetOption() {
  return {"set", "KEY=VALUE", "override one key, e.g. rv.enabled=false (applied last)", false, true};
}

}  // namespace rvlio::cli

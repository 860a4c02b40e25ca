#pragma once
// Option lists shared by several subcommands.
#include <string>
#include <vector>

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

inline OptionSpec OusterMetadataOption() {
  return {"ouster-metadata", "FILE",
          "Ouster sensor metadata JSON of a packet recording (default: NAME.json or NAME_0.json "
          "next to a .pcap, the bag's metadata topic); same as --set lidar.ouster_metadata=FILE",
          false, false};
}
// The --set overrides, then --ouster-metadata as lidar.ouster_metadata.
inline std::vector<std::string> OverridesOf(const Args& args) {
  std::vector<std::string> out = args.GetAll("set");
  if (args.Has("ouster-metadata")) out.push_back("lidar.ouster_metadata=" + args.Get("ouster-metadata"));
  return out;
}

}  // namespace rvlio::cli

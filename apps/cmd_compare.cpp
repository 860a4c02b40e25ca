#include "commands.h"
#include "common_options.h"

namespace rvlio::cli {

int CmdCompare(int argc, char** argv) {
  CommandSpec spec{"compare",
                   "Runs the standard variants (IESKF/smoother, RV off/on, refine) on one "
                   "sequence and tabulates ATE, RPE and speed.",
                   {{"bag", "FILE", "ROS1 bag", true},
                    {"gt", "TUM", "ground-truth trajectory", true},
                    ConfigOption(),
                    {"out", "DIR", "output folder", true}}};
  return EngineComesLater(spec, argc, argv, "comparison workflow (issue 7)");
}

}  // namespace rvlio::cli

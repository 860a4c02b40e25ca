#include "commands.h"
#include "common_options.h"

namespace rvlio::cli {

int CmdAblate(int argc, char** argv) {
  CommandSpec spec{"ablate",
                   "Runs a grid of sequences x variants x parameters; resumable.",
                   {{"grid", "FILE", "grid description (YAML)", true},
                    {"out", "DIR", "output folder", true},
                    {"jobs", "N", "parallel runs"}}};
  return EngineComesLater(spec, argc, argv, "ablation workflow (issue 7)");
}

}  // namespace rvlio::cli

#include "commands.h"
#include "common_options.h"

namespace rvlio::cli {

int CmdSimulate(int argc, char** argv) {
  CommandSpec spec{"simulate", "tunnel simulator (issue 3)", {}};
  return EngineComesLater(spec, argc, argv, "tunnel simulator (issue 3)");
}

}  // namespace rvlio::cli

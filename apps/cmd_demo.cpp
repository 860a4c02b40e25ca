#include "commands.h"
#include "common_options.h"

namespace rvlio::cli {

int CmdDemo(int argc, char** argv) {
  CommandSpec spec{"demo", "demo pipeline", {}};
  return EngineComesLater(spec, argc, argv, "demo pipeline");
}

}  // namespace rvlio::cli

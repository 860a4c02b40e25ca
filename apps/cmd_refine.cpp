#include "commands.h"
#include "common_options.h"

namespace rvlio::cli {

int CmdRefine(int argc, char** argv) {
  CommandSpec spec{"refine",
                   "Batch-refines a whole sequence starting from a previous run's trajectory.",
                   {{"bag", "FILE", "ROS1 bag with LiDAR and IMU topics", true},
                    {"init", "TUM", "initial trajectory (TUM format)", true},
                    ConfigOption(),
                    SetOption(),
                    {"out", "DIR", "output folder", true}}};
  return EngineComesLater(spec, argc, argv, "batch refinement engine (issue 6)");
}

}  // namespace rvlio::cli

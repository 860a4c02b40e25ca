// `rvlio demo`: simulates the default tunnel (SimulateRecording, with `rvlio
// simulate`'s lines), then runs `rvlio compare` on it in-process (IESKF and
// smoother with RV off and on, refine from the best) and prints the table and
// where the plots are; with the simulator's reference map
// (data/reference_map.pcd) the table has the map columns too.
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>

#include "commands.h"
#include "common_options.h"
#include "interrupt.h"

namespace rvlio::cli {

int CmdDemo(int argc, char** argv) {
  CommandSpec spec{"demo",
                   "Simulates the default tunnel (the paper's waypoints) and runs `rvlio compare` "
                   "on it: the IESKF and the smoother with the RV modules off and on, then refine "
                   "from the best; prints ATE/RPE against the ground truth and draws the plots.",
                   {{"out", "DIR", "output folder (default out/demo)"},
                    {"preset", "NAME", "simulator preset (default tunnel)"},
                    {"seed", "N", "simulator seed (default 1)"},
                    {"duration", "S", "simulated duration in seconds (default: the preset's)"}}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  const std::string out = args.Get("out", "out/demo"), preset = args.Get("preset", "tunnel");
  const std::string data_dir = out + "/data";
  experiments::CompareRequest compare;
  compare.bag = data_dir + "/" + preset + ".bag";
  compare.gt = data_dir + "/" + preset + "_gt.tum";
  compare.config_files = {data_dir + "/" + preset + ".yaml"};
  compare.out_dir = out;
  CompareOptions lines;
  lines.first_step = 2;
  lines.total_steps = 1 + experiments::CompareSteps(compare);

  SimulateArgs sim;
  sim.preset = preset;
  sim.name = preset;
  sim.out_dir = data_dir;
  sim.reference_map = true;
  sim.seed = 1;
  if (std::string err = ReadSeedOption(args, "seed", &sim.seed); !err.empty())
    return Fail("demo", err);
  if (std::string err = ReadDurationOption(args, &sim.duration_s); !err.empty())
    return Fail("demo", err);
  std::printf("[1/%d] simulating preset '%s' into %s\n", lines.total_steps, preset.c_str(),
              data_dir.c_str());
  std::fflush(stdout);
  {
    InterruptScope interrupt_scope;  // SIGINT/SIGTERM: stop, leave no half bag, exit 130/143
    if (int rc = SimulateOnDisk(std::move(sim)); rc != 0) return rc;
  }
  // The simulator's survey of the world (reference_map.pcd): the map columns.
  const std::string reference = data_dir + "/reference_map.pcd";
  if (std::filesystem::is_regular_file(reference)) compare.ref_map = reference;
  return CompareOnDisk(std::move(compare), lines);
}

}  // namespace rvlio::cli

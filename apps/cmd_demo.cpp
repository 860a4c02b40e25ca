// `rvlio demo`: simulates the default tunnel, then runs `rvlio compare` on it
// in-process (IESKF and smoother with RV off and on, refine from the best) and
// prints the table and where the plots are; with the simulator's reference
// map (data/reference_map.pcd) the table has the map columns too.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.h"
#include "common_options.h"
#include "compare_engine.h"

namespace rvlio::cli {
namespace {

// Calls another subcommand in-process with the given arguments.
int Invoke(int (*command)(int, char**), std::vector<std::string> args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return command(static_cast<int>(args.size()), argv.data());
}

}  // namespace

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
  CompareRequest compare;
  compare.bag = data_dir + "/" + preset + ".bag";
  compare.gt = data_dir + "/" + preset + "_gt.tum";
  compare.config_files = {data_dir + "/" + preset + ".yaml"};
  compare.out_dir = out;
  compare.first_step = 2;
  compare.total_steps = 1 + CompareSteps(compare);

  std::vector<std::string> sim_args = {"rvlio", "simulate", "--preset", preset, "--seed",
                                       args.Get("seed", "1"), "--reference-map", "--out",
                                       data_dir};
  if (args.Has("duration")) sim_args.insert(sim_args.end(), {"--duration", args.Get("duration")});
  std::printf("[1/%d] simulating preset '%s' into %s\n", compare.total_steps, preset.c_str(),
              data_dir.c_str());
  std::fflush(stdout);
  if (int rc = Invoke(CmdSimulate, sim_args); rc != 0) return rc;
  // The simulator's survey of the world (reference_map.pcd): the map columns.
  const std::string reference = data_dir + "/reference_map.pcd";
  if (std::filesystem::is_regular_file(reference)) compare.ref_map = reference;
  return RunCompare(compare);
}

}  // namespace rvlio::cli

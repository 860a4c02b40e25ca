// `rvlio compare`: argument parsing only; the workflow is compare_engine.h.
#include "cli.h"
#include "commands.h"
#include "common_options.h"
#include "compare_engine.h"
#include "time_range_options.h"

namespace rvlio::cli {

int CmdCompare(int argc, char** argv) {
  CommandSpec spec{
      "compare",
      "Runs the standard variants on one sequence - IESKF and smoother, each with the RV modules\n"
      "off and on - then `refine` from the best of them by ATE; evaluates each against the\n"
      "ground truth (se3 alignment) and writes OUT/<variant>/ (run outputs), OUT/compare.csv,\n"
      "compare.md, compare.json and OUT/plots/ (trajectories, RV profile, bar chart; needs\n"
      "python3 with matplotlib). Exit 0 when at least one variant ran, 1 when all failed,\n"
      "2 on bad input (before any run).",
      {{"bag", "PATH", "recording with LiDAR and IMU topics: ROS1 .bag, ROS 2 .db3, .mcap or bag folder", true},
       {"gt", "TUM", "ground-truth trajectory (TUM or KITTI, as rvlio eval)", true},
       {"ref-map", "FILE", "reference cloud (PCD/PLY, the ground truth's frame): adds map accuracy "
        "and completeness columns (as rvlio eval --map)"},
       ConfigOption(),
       SetOption(),
       {"out", "DIR", "output folder", true},
       StartOption(),
       DurationOption(),
       {"no-refine", "", "skip the refine step"},
       {"no-plots", "", "do not draw plots"},
       {"quiet", "", "no step lines or progress; the table is still printed"}}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  CompareRequest req;
  req.bag = args.Get("bag");
  req.gt = args.Get("gt");
  req.ref_map = args.Get("ref-map");
  req.out_dir = args.Get("out");
  req.config_files = args.GetAll("config");
  req.overrides = args.GetAll("set");
  req.refine = !args.Has("no-refine");
  req.plots = !args.Has("no-plots");
  req.quiet = args.Has("quiet");
  if (std::string err = ParseWindow(args, &req.window); !err.empty()) return Fail("compare", err);
  return RunCompare(req);
}

}  // namespace rvlio::cli

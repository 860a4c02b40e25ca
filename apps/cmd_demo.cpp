// `rvlio demo`: simulates the default tunnel, runs the IESKF with RV off and
// on and the smoother, and prints the accuracy of each against the ground truth.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "commands.h"
#include "common_options.h"
#include "run_pipeline.h"
#include "rvlio/eval/evaluate.h"
#include "rvlio/io/trajectory_io.h"

namespace rvlio::cli {
namespace {

// Calls another subcommand in-process with the given arguments.
int Invoke(int (*command)(int, char**), std::vector<std::string> args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return command(static_cast<int>(args.size()), argv.data());
}

struct Variant {
  const char* name;
  const char* label;
  std::vector<std::string> overrides;
};

void PrintRow(const char* label, const EvalResult& e, const RunOutcome& run) {
  std::printf("  %-22s %9.3f %9.3f %11.3f %10.3f %9.2f %8.1fx\n", label, e.ape_m.rmse,
              e.rpe.trans_m.rmse, e.along_axis.max_abs_m, e.end_point_error_m, run.median_ms,
              run.real_time_factor);
}

}  // namespace

int CmdDemo(int argc, char** argv) {
  CommandSpec spec{"demo",
                   "Simulates the default tunnel (the paper's waypoints), runs the IESKF with the "
                   "RV modules off and on and the smoother, and prints ATE/RPE against the ground "
                   "truth.",
                   {{"out", "DIR", "output folder (default out/demo)"},
                    {"preset", "NAME", "simulator preset (default tunnel)"},
                    {"seed", "N", "simulator seed (default 1)"},
                    {"duration", "S", "simulated duration in seconds (default: the preset's)"}}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  const std::string out = args.Get("out", "out/demo"), preset = args.Get("preset", "tunnel");
  const std::string data_dir = out + "/data";
  std::vector<std::string> sim_args = {"rvlio", "simulate", "--preset", preset, "--seed",
                                       args.Get("seed", "1"), "--out", data_dir};
  if (args.Has("duration")) sim_args.insert(sim_args.end(), {"--duration", args.Get("duration")});
  std::printf("[1/4] simulating preset '%s' into %s\n", preset.c_str(), data_dir.c_str());
  std::fflush(stdout);
  if (int rc = Invoke(CmdSimulate, sim_args); rc != 0) return rc;

  const std::string bag = data_dir + "/" + preset + ".bag", gt = data_dir + "/" + preset + "_gt.tum";
  StatusOr<Trajectory> truth = ReadTum(gt);
  if (!truth.ok()) return Fail("demo", truth.status().message());
  const std::vector<Variant> variants = {
      {"ieskf_rv_off", "IESKF, RV off", {"backend=ieskf", "rv.enabled=false"}},
      {"ieskf_rv_on", "IESKF, RV on (RV-LIO)", {"backend=ieskf", "rv.enabled=true"}},
      {"smoother_rv_on", "smoother, RV on", {"backend=smoother", "rv.enabled=true"}},
  };
  std::vector<std::pair<EvalResult, RunOutcome>> rows;
  for (size_t i = 0; i < variants.size(); ++i) {
    const Variant& v = variants[i];
    std::printf("[%zu/4] rvlio run %s\n", i + 2, v.name);
    std::fflush(stdout);
    RunRequest req{bag, out + "/" + v.name, {data_dir + "/" + preset + ".yaml"}, v.overrides};
    RunOutcome run;
    if (int rc = RunOdometryOnBag(req, &run); rc != 0) return rc;
    StatusOr<Trajectory> est = ReadTum(req.out_dir + "/trajectory.tum");
    if (!est.ok()) return Fail("demo", est.status().message(), 1);
    StatusOr<EvalResult> e = Evaluate(*truth, *est, EvalOptions());
    if (!e.ok()) return Fail("demo", e.status().message(), 1);
    rows.emplace_back(*e, run);
  }
  std::printf("\n  %-22s %9s %9s %11s %10s %9s %9s\n", "variant", "ATE [m]", "RPE [m]",
              "axis max[m]", "end [m]", "ms/scan", "speed");
  for (size_t i = 0; i < rows.size(); ++i) PrintRow(variants[i].label, rows[i].first, rows[i].second);
  std::printf("\n  ATE: RMSE after %s alignment; RPE: 1-frame translation RMSE; axis max: largest\n"
              "  error along the tunnel axis. Outputs: %s/<variant>/ (trajectory.tum, map.pcd,\n"
              "  scans.csv, summary.json). `rvlio refine` and `compare` extend this table.\n",
              rows.empty() ? "se3" : AlignModeName(rows.front().first.align), out.c_str());
  return 0;
}

}  // namespace rvlio::cli

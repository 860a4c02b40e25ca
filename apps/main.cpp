// rvlio: LiDAR-inertial odometry for weak-feature environments.
// This file only dispatches to the subcommands (apps/cmd_*.cpp).
#include <algorithm>
#include <csignal>
#include <cstring>
#include <iostream>

#include "commands.h"
#include "rvlio/version.h"

namespace {

struct Subcommand {
  const char* name;
  const char* summary;
  int (*fn)(int, char**);
};

constexpr Subcommand kSubcommands[] = {
    {"run", "run the odometry (IESKF or smoother) on a ROS1 or ROS 2 bag", rvlio::cli::CmdRun},
    {"live", "run the odometry on a ROS 1 or ROS 2 network and publish it (docs/live.md)",
     rvlio::cli::CmdLive},
    {"refine", "offline batch refinement of a whole sequence from an initial trajectory",
     rvlio::cli::CmdRefine},
    {"merge", "merge the chunk jobs of `refine --chunk K --of N` into one trajectory and map",
     rvlio::cli::CmdMerge},
    {"simulate", "simulate a tunnel flight: ROS1/ROS 2 bag, ground truth and sensor config",
     rvlio::cli::CmdSimulate},
    {"eval", "ATE/RPE of an estimated trajectory against ground truth (evo definitions)",
     rvlio::cli::CmdEval},
    {"compare", "run the standard variants on one sequence and tabulate their accuracy",
     rvlio::cli::CmdCompare},
    {"ablate", "run a grid of sequences x variants x parameters, resumable", rvlio::cli::CmdAblate},
    {"info", "list the topics, rates and point layouts of a ROS1 or ROS 2 bag", rvlio::cli::CmdInfo},
    {"calibrate-time", "estimate the LiDAR-IMU clock offset of a recording (offline)",
     rvlio::cli::CmdCalibrateTime},
    {"demo", "simulate the default tunnel and show what rvlio does with it", rvlio::cli::CmdDemo},
    {"report", "one self-contained report.html for a compare, demo, ablate or run folder",
     rvlio::cli::CmdReport},
    {"export", "convert a map PCD into LAS 1.4 (intensity, GPS time, extra bytes, CRS)",
     rvlio::cli::CmdExport},
};

void PrintHelp() {
  std::cout << "rvlio " << RVLIO_VERSION
            << " - LiDAR-inertial odometry for weak-feature environments (RV-LIO)\n\n"
               "usage: rvlio <command> [options]    (rvlio <command> --help for its options)\n\n"
               "commands:\n";
  size_t width = 0;  // the longest command name, then two spaces
  for (const auto& c : kSubcommands) width = std::max(width, std::strlen(c.name));
  for (const auto& c : kSubcommands) {
    std::cout << "  " << c.name << std::string(width + 2 - std::strlen(c.name), ' ') << c.summary
              << "\n";
  }
  std::cout << "\nexit status: 0 success, 2 bad input or configuration, 3 divergence detected\n"
               "(run, refine; outputs written), 1 internal failure, 130 / 143 stopped by\n"
               "SIGINT / SIGTERM (run, refine, compare, ablate, simulate, export; `live` ends\n"
               "by them: outputs written, exit 0)\n";
}

}  // namespace

int main(int argc, char** argv) {
  // A write past a file-size limit (ulimit -f) then fails with EFBIG and the
  // writers discard their temporary files, instead of the process dying with
  // a half-written file left behind.
  std::signal(SIGXFSZ, SIG_IGN);
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") ||
      !std::strcmp(argv[1], "help")) {
    PrintHelp();
    return argc < 2 ? 2 : 0;
  }
  if (!std::strcmp(argv[1], "--version")) {
    std::cout << "rvlio " << RVLIO_VERSION << "\n";
    return 0;
  }
  for (const auto& c : kSubcommands)
    if (!std::strcmp(argv[1], c.name)) return c.fn(argc, argv);
  std::cerr << "rvlio: error: unknown command '" << argv[1] << "' (see rvlio --help)\n";
  return 2;
}

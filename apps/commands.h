#pragma once
// The subcommands of docs/design.md "The command-line contract". Each returns the process exit
// status: 0 success, 2 bad input or configuration, 1 internal failure.
#include <cstdint>
#include <optional>
#include <string>

#include "cli.h"
#include "rvlio/api.h"
#include "rvlio/experiments/compare.h"

namespace rvlio::cli {

int CmdRun(int argc, char** argv);
int CmdRefine(int argc, char** argv);
int CmdMerge(int argc, char** argv);
int CmdSimulate(int argc, char** argv);
int CmdEval(int argc, char** argv);
int CmdCompare(int argc, char** argv);
int CmdAblate(int argc, char** argv);
int CmdInfo(int argc, char** argv);
int CmdCalibrateTime(int argc, char** argv);
int CmdDemo(int argc, char** argv);
int CmdReport(int argc, char** argv);
int CmdExport(int argc, char** argv);
int CmdLive(int argc, char** argv);

// `rvlio simulate`'s options (cmd_simulate.cpp), for demo too: --NAME (seed or
// flight-seed) and --duration as written; "" or the error message (nothing set).
std::string ReadSeedOption(const Args& args, const std::string& name, std::optional<int64_t>* seed);
std::string ReadDurationOption(const Args& args, std::optional<double>* duration_s);
// Every option of `rvlio simulate` into `sim` (SimulateRecording checks the
// values); "" or the error message.
std::string ReadSimulateArgs(const Args& args, SimulateArgs* sim);
// `rvlio simulate` after its arguments are parsed: SimulateRecording with the
// command's signals and lines; returns the exit status. Needs an InterruptScope.
int SimulateOnDisk(SimulateArgs sim);

// How `rvlio compare`'s lines look (demo continues its own step count).
struct CompareOptions {
  bool plots = true;
  bool quiet = false;  // no step lines; the table and the summary lines remain
  // Step numbering "[k/n] ...": the first step is first_step of total_steps
  // (total_steps 0: compare's own count).
  int first_step = 1;
  int total_steps = 0;
};
// `rvlio compare` after its arguments are parsed (cmd_compare.cpp):
// experiments::RunCompare with the command's signals and lines, the tables,
// the plots and report.html; returns the exit status (0: some variant ran
// without diverging, 1: every variant failed, 3: none ran cleanly but some
// diverged, 2: bad input before any run, nothing written).
int CompareOnDisk(experiments::CompareRequest request, const CompareOptions& options);

// Writes DIR/report.html for the folder `command` just wrote (compare, demo,
// ablate); a failure is a warning line, never the command's failure.
void WriteFolderReport(const std::string& command, const std::string& dir, bool quiet);

}  // namespace rvlio::cli

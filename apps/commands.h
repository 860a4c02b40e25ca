#pragma once
// The subcommands of docs/design.md "The command-line contract". Each returns the process exit
// status: 0 success, 2 bad input or configuration, 1 internal failure.
#include <cstdint>
#include <optional>
#include <string>

#include "cli.h"
#include "rvlio/api.h"

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

// Writes DIR/report.html for the folder `command` just wrote (compare, demo,
// ablate); a failure is a warning line, never the command's failure.
void WriteFolderReport(const std::string& command, const std::string& dir, bool quiet);

}  // namespace rvlio::cli

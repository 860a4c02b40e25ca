#pragma once
// The subcommands of docs/design.md "The command-line contract". Each returns the process exit
// status: 0 success, 2 bad input or configuration, 1 internal failure.
#include <string>

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

// Writes DIR/report.html for the folder `command` just wrote (compare, demo,
// ablate); a failure is a warning line, never the command's failure.
void WriteFolderReport(const std::string& command, const std::string& dir, bool quiet);

}  // namespace rvlio::cli

#pragma once
// The subcommands of docs/design.md section 7. Each returns the process exit
// status: 0 success, 2 bad input or configuration, 1 internal failure.
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

}  // namespace rvlio::cli

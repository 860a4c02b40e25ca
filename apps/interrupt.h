#pragma once
// SIGINT / SIGTERM for the commands that stop cleanly (run, refine, compare,
// ablate, simulate). While an InterruptScope lives, the first signal only
// records itself (an atomic store, async-signal-safe); the command polls
// Interrupted() at safe points, writes what it has and exits with
// InterruptExitCode() (130 for SIGINT, 143 for SIGTERM). A second signal
// aborts at once: it removes the file registered with SetAbortRemovePath(),
// forwards itself to the registered children and calls _exit(128 + signal).
// Every signal is forwarded to the registered child processes (ablate's
// cells), which run in their own process group so that a terminal's Ctrl-C
// reaches them once, through this process.
#include <sys/types.h>

#include <string>
#include <vector>

namespace rvlio::cli {

class InterruptScope {
 public:
  InterruptScope();   // installs the handlers; nested scopes share them
  ~InterruptScope();  // the outermost scope restores the previous handlers
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
};

bool Interrupted();
int InterruptSignal();                // 0 when none arrived
std::string InterruptSignalName();    // "SIGINT", "SIGTERM" ("" when none)
int InterruptExitCode();              // 128 + the signal
bool IsInterruptExit(int exit_code);  // 130 or 143

// Children to forward every signal to (at most kMaxForwardPids at a time).
constexpr int kMaxForwardPids = 64;
bool AddForwardPid(pid_t pid);
void RemoveForwardPid(pid_t pid);

// A file that an abort by the second signal removes (one at a time), e.g. the
// temporary file of a bag being written, then the folders around it that the
// command created, in order, each only when empty; "" clears it.
void SetAbortRemovePath(const std::string& path,
                        const std::vector<std::string>& empty_folders = {});

}  // namespace rvlio::cli

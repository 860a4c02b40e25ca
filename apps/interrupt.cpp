#include "interrupt.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

namespace rvlio::cli {
namespace {

// State shared with the signal handler: lock-free atomics and a fixed buffer
// only (async-signal-safe).
std::atomic<int> g_signal{0};
std::atomic<int> g_scopes{0};
std::atomic<pid_t> g_children[kMaxForwardPids];
constexpr size_t kMaxPath = 4096;
char g_abort_path[2][kMaxPath];   // double buffer: the handler reads the published one
std::atomic<int> g_abort_slot{-1};  // index of the published path, -1 none
struct sigaction g_previous_int, g_previous_term;

static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");

void Forward(int sig) {
  for (auto& child : g_children) {
    const pid_t pid = child.load();
    if (pid > 0) ::kill(pid, sig);
  }
}

// The published abort list: a file, then folders, each ended by '\0', the
// list by an empty entry (unlink and rmdir are async-signal-safe; rmdir
// removes only an empty folder).
void RemoveAbortPaths(const char* list) {
  ::unlink(list);
  for (const char* p = list; *p != '\0';) {
    while (*p != '\0') ++p;
    ++p;  // the next entry
    if (*p != '\0') ::rmdir(p);
  }
}

extern "C" void OnSignal(int sig) {
  const int saved_errno = errno;
  Forward(sig);
  int none = 0;
  if (!g_signal.compare_exchange_strong(none, sig)) {  // the second signal: abort now
    const int slot = g_abort_slot.load();
    if (slot >= 0) RemoveAbortPaths(g_abort_path[slot]);
    ::_exit(128 + sig);
  }
  errno = saved_errno;
}

void Install(int sig, struct sigaction* previous) {
  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  ::sigaction(sig, &sa, previous);
}

}  // namespace

InterruptScope::InterruptScope() {
  if (g_scopes.fetch_add(1) > 0) return;
  g_signal.store(0);
  Install(SIGINT, &g_previous_int);
  Install(SIGTERM, &g_previous_term);
}

InterruptScope::~InterruptScope() {
  if (g_scopes.fetch_sub(1) != 1) return;
  ::sigaction(SIGINT, &g_previous_int, nullptr);
  ::sigaction(SIGTERM, &g_previous_term, nullptr);
}

bool Interrupted() { return g_signal.load() != 0; }

int InterruptSignal() { return g_signal.load(); }

std::string InterruptSignalName() {
  switch (g_signal.load()) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    default: return "";
  }
}

int InterruptExitCode() { return 128 + g_signal.load(); }

bool IsInterruptExit(int exit_code) {
  return exit_code == 128 + SIGINT || exit_code == 128 + SIGTERM;
}

bool AddForwardPid(pid_t pid) {
  for (auto& child : g_children) {
    pid_t empty = 0;
    if (child.compare_exchange_strong(empty, pid)) return true;
  }
  return false;
}

void RemoveForwardPid(pid_t pid) {
  for (auto& child : g_children) {
    pid_t expected = pid;
    if (child.compare_exchange_strong(expected, 0)) return;
  }
}

void SetAbortRemovePath(const std::string& path, const std::vector<std::string>& empty_folders) {
  std::string list = path + '\0';
  for (const std::string& folder : empty_folders)
    if (!folder.empty()) list += folder + '\0';
  list += '\0';
  if (path.empty() || list.size() > kMaxPath) {
    g_abort_slot.store(-1);
    return;
  }
  const int slot = g_abort_slot.load() == 0 ? 1 : 0;  // never the one the handler may read
  std::memcpy(g_abort_path[slot], list.data(), list.size());
  g_abort_slot.store(slot);
}

}  // namespace rvlio::cli

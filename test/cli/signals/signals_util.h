#pragma once
// Helpers for the interruption tests: the built `rvlio` as a child process
// (fork + exec, no shell, so that signals reach it directly) and polling for
// files instead of sleeping for a fixed time.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "cli/cli_util.h"

namespace rvlio::signals_test {

using testing_cli::ReadFile;

// `PROGRAM ARGS...` (argv_s[0]: a path, or a name looked up in PATH) with
// stdout and stderr into files; with own_group, in a process group of its
// own (pid = group id), so that kill(-pid, ...) reaches the children it starts.
inline pid_t SpawnProgram(std::vector<std::string> argv_s, const std::string& out_path,
                          const std::string& err_path, bool own_group = false) {
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  if (own_group) ::setpgid(0, 0);
  const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (out < 0 || err < 0) ::_exit(97);
  ::dup2(out, STDOUT_FILENO);
  ::dup2(err, STDERR_FILENO);
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::execvp(argv[0], argv.data());
  ::_exit(98);
}

// `rvlio ARGS...` with stdout and stderr into files.
inline pid_t Spawn(const std::vector<std::string>& args, const std::string& out_path,
                   const std::string& err_path) {
  std::vector<std::string> argv_s = {RVLIO_BIN};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  return SpawnProgram(std::move(argv_s), out_path, err_path);
}

// The exit status of a child: its exit code, or 128 + the signal that killed it.
inline int ExitStatus(int raw) {
  return WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
}

inline int Wait(pid_t pid) {
  int raw = 0;
  ::waitpid(pid, &raw, 0);
  return ExitStatus(raw);
}

// Polls `ready` every 5 ms until it holds (true) or the child ends (false,
// with its status in *exit_status), at most 300 s.
inline bool WaitUntil(pid_t pid, const std::function<bool()>& ready, int* exit_status) {
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(300)) {
    if (ready()) return true;
    int raw = 0;
    if (::waitpid(pid, &raw, WNOHANG) == pid) {
      *exit_status = ExitStatus(raw);
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

// The complete lines of a text (a torn last line is dropped).
inline std::vector<std::string> CompleteLines(const std::string& text) {
  std::vector<std::string> lines;
  size_t start = 0;
  for (size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1)
    lines.push_back(text.substr(start, end - start + 1));
  return lines;
}

inline int CountLines(const std::string& path) {
  return static_cast<int>(CompleteLines(ReadFile(path)).size());
}

inline bool Exists(const std::string& path) { return ::access(path.c_str(), F_OK) == 0; }

}  // namespace rvlio::signals_test

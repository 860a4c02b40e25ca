#include "plot_runner.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <system_error>

extern char** environ;

namespace rvlio::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* kScriptEnv = "RVLIO_PLOT_SCRIPT";
constexpr const char* kSystemPython = "/usr/bin/python3";
constexpr int kExitNoMatplotlib = 3;  // rvlio_plot.py: matplotlib/numpy not available

struct ChildResult {
  bool started = false;
  int exit_code = -1;  // -1: killed by a signal
  std::string err;     // the child's stderr
  std::string spawn_error;
};

// Directory of the running executable, or "" when /proc is unavailable.
fs::path ExecutableDir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe.parent_path();
}

bool IsRegularFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

// Reads everything from `fd` until EOF (the child's stderr; small).
std::string Drain(int fd) {
  std::string text;
  char buffer[4096];
  for (;;) {
    const ssize_t n = read(fd, buffer, sizeof(buffer));
    if (n > 0) text.append(buffer, static_cast<size_t>(n));
    else if (n < 0 && errno == EINTR) continue;
    else break;
  }
  return text;
}

// Runs `argv` (argv[0] is the program; searched on PATH when it has no slash)
// with stdout to /dev/null and stderr captured. No shell is involved.
ChildResult Spawn(const std::vector<std::string>& args) {
  ChildResult result;
  int pipe_fds[2];
  // Close-on-exec, so that children started concurrently by other threads do
  // not inherit the write end (which would delay EOF here).
  if (pipe2(pipe_fds, O_CLOEXEC) != 0) {
    result.spawn_error = std::string("pipe: ") + std::strerror(errno);
    return result;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDERR_FILENO);  // clears CLOEXEC
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  std::fflush(nullptr);  // nothing buffered may be duplicated into the child
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(pipe_fds[1]);
  if (rc != 0) {
    close(pipe_fds[0]);
    result.spawn_error = "cannot start " + args[0] + ": " + std::strerror(rc);
    return result;
  }
  result.started = true;
  result.err = Drain(pipe_fds[0]);
  close(pipe_fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

// The last non-empty line of the script's stderr without its "rvlio_plot: "
// prefix (a Python traceback ends with the exception line).
std::string LastLine(const std::string& text) {
  size_t end = text.find_last_not_of(" \n\r\t");
  if (end == std::string::npos) return "";
  const size_t begin = text.rfind('\n', end);
  std::string line = text.substr(begin == std::string::npos ? 0 : begin + 1, end + 1 -
                                 (begin == std::string::npos ? 0 : begin + 1));
  const std::string prefix = "rvlio_plot: ";
  if (line.rfind(prefix, 0) == 0) line = line.substr(prefix.size());
  return line;
}

std::string Interpreter() {
  return access(kSystemPython, X_OK) == 0 ? kSystemPython : "python3";
}

// `rvlio_plot.py check`, whose answer holds for the whole process.
PlotResult Probe(const std::string& script) {
  PlotResult probe;
  if (script.empty()) {
    probe.message = std::string("rvlio_plot.py not found (set ") + kScriptEnv +
                    " or keep scripts/ next to the build folder)";
    return probe;
  }
  const ChildResult child = Spawn({Interpreter(), script, "check"});
  if (!child.started) {
    probe.message = child.spawn_error;
  } else if (child.exit_code == kExitNoMatplotlib) {
    probe.message = LastLine(child.err);
  } else if (child.exit_code != 0) {
    probe.message = script + " check failed (exit " + std::to_string(child.exit_code) + ")" +
                    (child.err.empty() ? "" : ": " + LastLine(child.err));
  } else {
    probe.ok = true;
  }
  return probe;
}

}  // namespace

std::string FindPlotScript() {
  if (const char* env = std::getenv(kScriptEnv); env != nullptr && *env != '\0')
    return IsRegularFile(env) ? std::string(env) : std::string();
  const fs::path dir = ExecutableDir();
  if (dir.empty()) return "";
  for (const fs::path& candidate : {dir / ".." / ".." / "scripts" / "rvlio_plot.py",
                                    dir / ".." / "share" / "rvlio" / "rvlio_plot.py"}) {
    if (IsRegularFile(candidate)) return candidate.lexically_normal().string();
  }
  return "";
}

PlotResult RunPlotScript(const std::vector<std::string>& args) {
  const std::string script = FindPlotScript();
  // Thread-safe one-time probe; the environment does not change in a run.
  static const PlotResult availability = Probe(script);
  PlotResult result;
  if (!availability.ok) {
    result.message = availability.message;
    return result;
  }
  std::vector<std::string> argv = {Interpreter(), script};
  argv.insert(argv.end(), args.begin(), args.end());
  const ChildResult child = Spawn(argv);
  result.ran = child.started;
  result.ok = child.started && child.exit_code == 0;
  if (!child.started) {
    result.message = child.spawn_error;
  } else if (!result.ok) {
    const std::string why = LastLine(child.err);
    result.message = (child.exit_code < 0 ? std::string("killed by a signal")
                                          : "exit " + std::to_string(child.exit_code)) +
                     (why.empty() ? "" : ": " + why);
  }
  return result;
}

}  // namespace rvlio::cli

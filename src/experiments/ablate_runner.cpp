#include "rvlio/experiments/ablate_runner.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include "rvlio/experiments/ablate_cells.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/outputs/summary_json.h"

extern char** environ;

namespace rvlio::experiments::ablate {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

constexpr size_t kTailLines = 12;
constexpr size_t kTailChars = 2000;

// One child process: `rvlio ARGS` with stdout+stderr into `log`.
struct Job {
  std::string name;
  std::vector<std::string> args;
  std::string log;
  std::function<bool()> prepare;  // false: do not start (already recorded)
  // Called with the raw wait status (or -1 when the spawn failed) and the
  // wall seconds; returns true when the item succeeded.
  std::function<bool(int, double)> finish;
  // Instead of finish() for a child that a signal stopped: removes what it
  // left, so the item is run again next time.
  std::function<void()> discard;
};

// A child stopped by the signal forwarded to it (exit 128 + SIGINT or
// SIGTERM, the contract's 130 / 143, or killed by it).
bool StoppedBySignal(int status) {
  if (WIFEXITED(status))
    return WEXITSTATUS(status) == 128 + SIGINT || WEXITSTATUS(status) == 128 + SIGTERM;
  return WIFSIGNALED(status) && (WTERMSIG(status) == SIGINT || WTERMSIG(status) == SIGTERM);
}

// Blocks SIGINT and SIGTERM while alive: a signal arriving between the
// hooks' Stopped() check and ChildStarted() of a new child is delivered after
// it, and so forwarded to that child too (by a caller that forwards signals).
class BlockInterrupts {
 public:
  BlockInterrupts() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, &saved_);
  }
  ~BlockInterrupts() { pthread_sigmask(SIG_SETMASK, &saved_, nullptr); }
  BlockInterrupts(const BlockInterrupts&) = delete;
  BlockInterrupts& operator=(const BlockInterrupts&) = delete;

 private:
  sigset_t saved_;
};

pid_t Spawn(const std::string& program, const Job& job) {
  std::vector<std::string> argv_s = {program};
  argv_s.insert(argv_s.end(), job.args.begin(), job.args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, job.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  // Its own process group, so that a terminal's Ctrl-C reaches it once,
  // forwarded by this process (interrupt.h); no signal blocked.
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK);
  posix_spawnattr_setpgroup(&attr, 0);
  sigset_t none;
  sigemptyset(&none);
  posix_spawnattr_setsigmask(&attr, &none);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, program.c_str(), &actions, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  return rc == 0 ? pid : -1;
}

struct JobCounts {
  int ok = 0, failed = 0, stopped = 0;  // stopped: by a signal, discarded
  void Add(bool good) { (good ? ok : failed)++; }
};

// Starts a job; false when it did not start (recorded by prepare() or
// finish(-1)). Called with signals blocked (BlockInterrupts).
bool Start(Job& job, const RunnerOptions& options, RunnerHooks* hooks, JobCounts* counts,
           pid_t* pid_out) {
  if (job.prepare && !job.prepare()) {  // recorded as failed by prepare()
    counts->Add(false);
    hooks->Finished(job.name, false, 0.0);
    return false;
  }
  const pid_t pid = Spawn(options.rvlio_bin, job);
  if (pid < 0 || !hooks->ChildStarted(pid)) {
    if (pid > 0) {  // more children than the caller follows: not started
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
    const bool good = job.finish(-1, 0.0);
    counts->Add(good);
    hooks->Finished(job.name, good, 0.0);
    return false;
  }
  *pid_out = pid;
  return true;
}

// Runs the jobs `parallel` at a time. After a stop (a signal the caller
// forwards to the running children) no job starts; the running ones end, and
// those the signal stopped are discarded.
JobCounts RunJobs(std::vector<Job>& jobs, const RunnerOptions& options, RunnerHooks* hooks) {
  struct Running {
    size_t index;
    Clock::time_point t0;
  };
  std::map<pid_t, Running> running;
  size_t next = 0;
  JobCounts counts;
  const size_t parallel = static_cast<size_t>(std::max(1, options.jobs));
  while ((next < jobs.size() && !hooks->Stopped()) || !running.empty()) {
    {
      BlockInterrupts block;
      for (; running.size() < parallel && next < jobs.size() && !hooks->Stopped(); ++next) {
        pid_t pid = -1;
        if (Start(jobs[next], options, hooks, &counts, &pid))
          running[pid] = {next, Clock::now()};
      }
    }
    hooks->Running(static_cast<int>(running.size()));
    if (running.empty()) continue;
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;  // ECHILD: nothing left to wait for
    }
    hooks->ChildEnded(pid);
    auto it = running.find(pid);
    if (it == running.end()) continue;
    const double wall = std::chrono::duration<double>(Clock::now() - it->second.t0).count();
    Job& job = jobs[it->second.index];
    running.erase(it);
    if (hooks->Stopped() && StoppedBySignal(status)) {
      if (job.discard) job.discard();
      ++counts.stopped;
      hooks->StoppedItem(job.name);
      continue;
    }
    const bool good = job.finish(status, wall);
    counts.Add(good);
    hooks->Finished(job.name, good, wall);
  }
  return counts;
}

// The last lines of a log, for cell.json.
std::string Tail(const std::string& text) {
  size_t pos = text.size();
  for (size_t lines = 0; pos > 0 && lines <= kTailLines;) {
    --pos;
    if (text[pos] == '\n' && pos + 1 < text.size()) ++lines;
    if (lines > kTailLines) {
      ++pos;
      break;
    }
  }
  std::string tail = text.substr(pos);
  if (tail.size() > kTailChars) tail = tail.substr(tail.size() - kTailChars);
  return tail;
}

// "exited with status 2", "killed by signal 11 (Segmentation fault)", ...
std::string Describe(int status, int* exit_code) {
  *exit_code = -1;
  if (status == -1) return "could not be started";
  if (WIFEXITED(status)) {
    *exit_code = WEXITSTATUS(status);
    return "exited with status " + std::to_string(*exit_code);
  }
  if (WIFSIGNALED(status))
    return "killed by signal " + std::to_string(WTERMSIG(status)) + " (" +
           strsignal(WTERMSIG(status)) + ")";
  return "ended abnormally";
}

// True when the cell finished (done or diverged); a failed write goes to the hooks.
bool Recorded(const StatusOr<CellStatus>& status, RunnerHooks* hooks) {
  if (!status.ok()) hooks->RecordError(status.status());
  return status.ok() && Finished(*status);
}

// Records a cell that could not run because its data is missing or failed.
bool RecordDataMissing(const Cell& cell, const DataItem& d, RunnerHooks* hooks) {
  std::error_code ec;
  fs::create_directories(cell.dir, ec);
  return Recorded(RecordDataFailure(cell, d, Tail(ReadFileText(d.dir + "/simulate.log"))), hooks);
}

bool CellDone(const Cell& cell) { return Finished(ReadCellStatus(cell)); }

bool FinishCell(const Cell& cell, int status, double wall_s, const RunnerOptions& options,
                RunnerHooks* hooks) {
  CellRunEnd end;
  int exit_code = -1;
  end.how = Describe(status, &exit_code);
  if (exit_code >= 0) end.exit_code = exit_code;
  end.diverged = exit_code == options.diverged_exit_code;  // ran to the end: metrics kept
  end.wall_s = wall_s;
  end.log_tail = Tail(ReadFileText(cell.dir + "/run.log"));
  return Recorded(RecordCell(cell, end), hooks);
}

bool DataReady(const DataItem& d) {
  const json marker = ReadJsonFile(d.Marker());
  return marker.is_object() && marker.value("hash", "") == d.hash &&
         marker.value("status", "") == "done" && fs::is_regular_file(d.bag);
}

bool FinishData(const DataItem& d, int status, double wall_s) {
  int exit_code = -1;
  const std::string how = Describe(status, &exit_code);
  const bool ok = exit_code == 0 && fs::is_regular_file(d.bag) && fs::is_regular_file(d.gt) &&
                  fs::is_regular_file(d.sensor_config);
  const json marker = {{"format", 1},
                       {"id", d.id},
                       {"hash", d.hash},
                       {"status", ok ? "done" : "failed"},
                       {"error", ok ? "" : "rvlio simulate " + how},
                       {"wall_s", wall_s},
                       {"simulate_argv", d.simulate_args}};
  const Status s = WriteFileAtomically(d.Marker(), JsonText(marker) + "\n");
  return ok && s.ok();
}

Job DataJob(const DataItem& d) {
  Job job;
  job.name = d.id;
  job.args = d.simulate_args;
  job.log = d.dir + "/simulate.log";
  job.prepare = [&d] {
    std::error_code ec;
    fs::create_directories(d.dir, ec);
    fs::remove(d.Marker(), ec);
    return true;
  };
  job.finish = [&d](int status, double wall) { return FinishData(d, status, wall); };
  job.discard = [&d] {  // simulate removes its half bag itself
    std::error_code ec;
    fs::remove(d.Marker(), ec);
  };
  return job;
}

Job CellJob(const Plan& plan, const Cell& cell, const RunnerOptions& options, RunnerHooks* hooks) {
  Job job;
  job.name = cell.id;
  job.args = cell.RunArgs();
  job.log = cell.dir + "/run.log";
  job.prepare = [&plan, &cell, hooks] {
    std::error_code ec;
    fs::create_directories(cell.dir, ec);
    fs::remove(cell.CellJson(), ec);
    fs::remove_all(cell.RunDir(), ec);
    if (cell.data_index >= 0 && !DataReady(plan.data[cell.data_index])) {
      RecordDataMissing(cell, plan.data[cell.data_index], hooks);
      return false;
    }
    return true;
  };
  job.finish = [&cell, &options, hooks](int status, double wall) {
    return FinishCell(cell, status, wall, options, hooks);
  };
  job.discard = [&cell] {  // no half result: the cell runs again next time
    std::error_code ec;
    fs::remove(cell.CellJson(), ec);
    fs::remove_all(cell.RunDir(), ec);
  };
  return job;
}

// Runs the given jobs under one progress display; updates the counts.
void RunBatch(std::vector<Job> jobs, int total, int skipped, const std::string& what,
              const RunnerOptions& options, RunnerHooks* hooks, RunCounts* counts) {
  if (jobs.empty()) return;
  hooks->BatchStarted(what, total, skipped);
  const JobCounts c = RunJobs(jobs, options, hooks);
  hooks->BatchEnded();
  if (counts != nullptr) {
    counts->done += c.ok;
    counts->failed += c.failed;
    counts->interrupted += c.stopped;
    counts->not_started += static_cast<int>(jobs.size()) - c.ok - c.failed - c.stopped;
  }
}

}  // namespace

RunCounts RunPlan(const Plan& plan, const RunnerOptions& options, RunnerHooks* hooks) {
  RunnerHooks none;
  if (hooks == nullptr) hooks = &none;
  RunCounts counts;
  counts.total = static_cast<int>(plan.cells.size());
  // Data needed by a cell that is not finished yet.
  std::vector<bool> needed(plan.data.size(), false);
  std::vector<Job> cell_jobs;
  for (const Cell& c : plan.cells) {
    if (CellDone(c)) {
      ++counts.skipped;
      continue;
    }
    if (c.data_index >= 0) needed[c.data_index] = true;
    cell_jobs.push_back(CellJob(plan, c, options, hooks));
  }
  std::vector<Job> data_jobs;
  int data_total = 0, data_skipped = 0;
  for (size_t i = 0; i < plan.data.size(); ++i) {
    if (!needed[i]) continue;
    ++data_total;
    if (DataReady(plan.data[i]))
      ++data_skipped;
    else
      data_jobs.push_back(DataJob(plan.data[i]));
  }
  RunBatch(std::move(data_jobs), data_total, data_skipped, "data", options, hooks, nullptr);
  RunBatch(std::move(cell_jobs), counts.total, counts.skipped, "cell", options, hooks, &counts);
  return counts;
}

bool RunOne(const Plan& plan, const std::string& id, const RunnerOptions& options,
            RunnerHooks* hooks, RunCounts* counts) {
  RunnerHooks none;
  if (hooks == nullptr) hooks = &none;
  for (const DataItem& d : plan.data)
    if (d.id == id) {
      if (!DataReady(d))
        RunBatch({DataJob(d)}, 1, 0, "data", options, hooks, counts);
      else if (counts != nullptr)
        ++counts->skipped;
      return true;
    }
  for (const Cell& c : plan.cells)
    if (c.id == id) {
      counts->total = 1;
      if (CellDone(c)) {
        ++counts->skipped;
        return true;
      }
      // Simulate missing data (not data that already failed: parallel
      // Snakemake cell jobs of one sequence must not simulate it twice).
      if (c.data_index >= 0 && !fs::exists(plan.data[c.data_index].Marker()))
        RunBatch({DataJob(plan.data[c.data_index])}, 1, 0, "data", options, hooks, nullptr);
      RunBatch({CellJob(plan, c, options, hooks)}, 1, 0, "cell", options, hooks, counts);
      return true;
    }
  return false;
}

}  // namespace rvlio::experiments::ablate

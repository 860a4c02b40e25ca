#pragma once
// CPU time of the calling thread: the cost of a piece of work, unaffected by
// other processes competing for the cores; and the wall time since a moment,
// which runs report per phase and per run.
#include <chrono>
#include <ctime>

namespace rvlio {

// Milliseconds of CPU time consumed by the calling thread so far.
inline double ThreadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// Seconds of wall (steady clock) time since t0.
inline double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace rvlio

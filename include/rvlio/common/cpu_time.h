#pragma once
// CPU time of the calling thread: the cost of a piece of work, unaffected by
// other processes competing for the cores (wall time is reported per run).
#include <ctime>

namespace rvlio {

// Milliseconds of CPU time consumed by the calling thread so far.
inline double ThreadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

}  // namespace rvlio

#include "rvlio/common/parallel.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <thread>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

namespace rvlio {

int ResolveThreads(int threads) {
  if (threads > 0) return threads;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

int ParallelSlots(int threads, int count) { return std::max(1, std::min(threads, count)); }

namespace {
// CPU ms of helper threads on this thread's loops (ParallelWorkerCpuMs).
thread_local double worker_cpu_ms = 0.0;
}  // namespace

double ParallelWorkerCpuMs() { return worker_cpu_ms; }

// An arena of `slots` threads (the caller's included) bounds the concurrency
// whatever TBB's global pool holds; its thread index is the slot. One index
// per task (simple_partitioner, grain 1): the items (scans) differ in cost, so
// idle threads take the next index, as a shared counter would.
void ParallelFor(int begin, int end, int threads,
                 const std::function<void(int index, int slot)>& fn) {
  if (end <= begin) return;
  const int slots = ParallelSlots(threads, end - begin);
  if (slots == 1) {
    for (int i = begin; i < end; ++i) fn(i, 0);
    return;
  }
  // Tasks that run on a thread other than the caller's add their CPU time
  // (nanoseconds) here; the caller's own is in its ThreadCpuMs already.
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<int64_t> worker_ns{0};
  tbb::task_arena arena(slots);
  arena.execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<int>(begin, end, 1),
        [&](const tbb::blocked_range<int>& range) {
          const int slot = tbb::this_task_arena::current_thread_index();
          const bool helper = std::this_thread::get_id() != caller;
          const double start_ms = helper ? ThreadCpuMs() : 0.0;
          for (int i = range.begin(); i != range.end(); ++i) fn(i, slot);
          if (helper)
            worker_ns.fetch_add(static_cast<int64_t>((ThreadCpuMs() - start_ms) * 1e6),
                                std::memory_order_relaxed);
        },
        tbb::simple_partitioner());
  });
  worker_cpu_ms += static_cast<double>(worker_ns.load()) * 1e-6;
}

}  // namespace rvlio

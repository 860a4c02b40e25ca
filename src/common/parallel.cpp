#include "rvlio/common/parallel.h"

#include <algorithm>
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
  tbb::task_arena arena(slots);
  arena.execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<int>(begin, end, 1),
        [&](const tbb::blocked_range<int>& range) {
          const int slot = tbb::this_task_arena::current_thread_index();
          for (int i = range.begin(); i != range.end(); ++i) fn(i, slot);
        },
        tbb::simple_partitioner());
  });
}

}  // namespace rvlio

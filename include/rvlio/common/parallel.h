#pragma once
// The project's one facility for parallel loops (oneTBB underneath; the TBB
// headers stay in parallel.cpp). Used by batch refine for deskew and
// association over scans; any other loop over independent items belongs here
// too, not on hand-made threads.
//
// Determinism: every index runs exactly once, and a loop body that writes
// only its own index's results (and uses per-slot scratch that it resets)
// gives the same output for any thread count and any schedule.
#include <functional>

#include "rvlio/common/cpu_time.h"

namespace rvlio {

// The thread count a `threads` option means: itself when > 0, else the
// number of hardware threads (at least 1).
int ResolveThreads(int threads);

// fn(index, slot) for every index in [begin, end), on at most `threads`
// threads. slot, in [0, ParallelSlots(threads, end - begin)), names the
// thread running the call: two calls running at the same time never share a
// slot, so per-slot workspaces need no locking. threads <= 1 (or a single
// index): in index order on the calling thread, slot 0.
void ParallelFor(int begin, int end, int threads,
                 const std::function<void(int index, int slot)>& fn);

// The number of slots ParallelFor uses for `count` indices on `threads`.
int ParallelSlots(int threads, int count);

// Milliseconds of CPU time that other threads have spent so far running the
// calling thread's ParallelFor loops (a per-thread counter, only ever
// increased). With ThreadCpuMs it gives the cost of a piece of work that
// ran part of itself on helper threads: WorkCpuMs below.
double ParallelWorkerCpuMs();

// CPU time of the calling thread plus that of the helper threads its
// ParallelFor loops used, in ms: differences of it are a computation's whole
// CPU cost for any thread count (ThreadCpuMs alone misses the helpers').
inline double WorkCpuMs() { return ThreadCpuMs() + ParallelWorkerCpuMs(); }

}  // namespace rvlio

// ParallelFor: every index once, slots within bounds and never shared by two
// running calls, and per-index results independent of the thread count.
#include <atomic>
#include <cstdio>
#include <cmath>
#include <mutex>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/common/parallel.h"

namespace rvlio {
namespace {

TEST(ParallelFor, RunsEveryIndexExactlyOnceWithSlotsInRange) {
  for (int threads : {1, 2, 3, 8}) {
    const int begin = 5, end = 205;
    std::vector<std::atomic<int>> runs(end);
    std::atomic<bool> slot_ok(true);
    const int slots = ParallelSlots(threads, end - begin);
    ParallelFor(begin, end, threads, [&](int i, int slot) {
      runs[i]++;
      if (slot < 0 || slot >= slots) slot_ok = false;
    });
    for (int i = 0; i < end; ++i) EXPECT_EQ(runs[i].load(), i < begin ? 0 : 1) << i;
    EXPECT_TRUE(slot_ok.load()) << threads;
  }
}

TEST(ParallelFor, ASlotIsNeverInUseTwiceAtOnce) {
  const int threads = 4;
  std::vector<std::atomic<int>> busy(ParallelSlots(threads, 400));
  std::atomic<int> clashes(0);
  ParallelFor(0, 400, threads, [&](int i, int slot) {
    if (busy[slot]++ != 0) ++clashes;
    volatile double x = 0.0;
    for (int k = 0; k < 2000 + 50 * (i % 7); ++k) x = x + std::sqrt(static_cast<double>(k));
    busy[slot]--;
  });
  EXPECT_EQ(clashes.load(), 0);
}

// Per-slot scratch reused across indices, results per index: the same bits
// with one thread and with several.
TEST(ParallelFor, PerIndexResultsDoNotDependOnTheThreadCount) {
  auto run = [](int threads) {
    std::vector<double> out(300);
    std::vector<std::vector<double>> scratch(ParallelSlots(threads, 300));
    ParallelFor(0, 300, threads, [&](int i, int slot) {
      std::vector<double>& s = scratch[slot];
      s.assign(50 + i % 13, 0.0);
      for (size_t k = 0; k < s.size(); ++k) s[k] = std::sin(0.1 * i + 0.01 * k);
      double sum = 0.0;
      for (double v : s) sum += v;
      out[i] = sum;
    });
    return out;
  };
  const std::vector<double> one = run(1);
  EXPECT_EQ(run(2), one);
  EXPECT_EQ(run(4), one);
}

// Busy CPU work of about `ms` milliseconds on the calling thread.
double Spin(double ms) {
  const double until = ThreadCpuMs() + ms;
  double x = 1.0;
  while (ThreadCpuMs() < until) x = std::sqrt(x + 1.0);
  return x;
}

// WorkCpuMs counts the items that ran on helper threads: its difference over
// a loop is at least the CPU the items used wherever they ran, and the helper
// counter grows by at least the items that ran on another thread.
TEST(ParallelFor, WorkCpuCountsTheHelperThreads) {
  const std::thread::id caller = std::this_thread::get_id();
  std::mutex mutex;
  double items_ms = 0.0, helper_items_ms = 0.0;
  const double work_before = WorkCpuMs(), helper_before = ParallelWorkerCpuMs();
  ParallelFor(0, 16, 2, [&](int, int) {
    const double t0 = ThreadCpuMs();
    volatile double sink = Spin(5.0);
    (void)sink;
    const double used = ThreadCpuMs() - t0;
    std::lock_guard<std::mutex> lock(mutex);
    items_ms += used;
    if (std::this_thread::get_id() != caller) helper_items_ms += used;
  });
  EXPECT_GE(WorkCpuMs() - work_before, 0.99 * items_ms);
  EXPECT_GE(ParallelWorkerCpuMs() - helper_before, 0.99 * helper_items_ms);
  std::printf("[ cpu ] items %.1f ms, %.1f ms of them on a helper thread\n", items_ms,
              helper_items_ms);
  // One thread: everything on the caller, the helper counter unchanged.
  const double helper_mid = ParallelWorkerCpuMs();
  ParallelFor(0, 4, 1, [&](int, int) { Spin(1.0); });
  EXPECT_EQ(ParallelWorkerCpuMs(), helper_mid);
}

TEST(ParallelFor, EmptyRangeAndThreadResolution) {
  int calls = 0;
  ParallelFor(3, 3, 4, [&](int, int) { ++calls; });
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(ResolveThreads(3), 3);
  EXPECT_GE(ResolveThreads(0), 1);
  EXPECT_EQ(ParallelSlots(8, 2), 2);
  EXPECT_EQ(ParallelSlots(0, 10), 1);
}

}  // namespace
}  // namespace rvlio

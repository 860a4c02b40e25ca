// ParallelFor: every index once, slots within bounds and never shared by two
// running calls, and per-index results independent of the thread count.
#include <atomic>
#include <cmath>
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

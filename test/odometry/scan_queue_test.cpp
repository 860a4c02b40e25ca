// The scan queue's stamp checks (odometry/scan_frontend.h ScanQueue,
// lidar/scan_order.h): a stream of 10 Hz scans with a 200 Hz IMU, received
// in the order a recording gives them (a scan once its sweep has ended), with
// single stamps edited as a bit flip in a header stamp would: a stamp that
// repeats or goes back is skipped as out of order; a stamp that jumps ahead
// of the scan period and of the IMU costs only its own scan.
#include <algorithm>
#include <functional>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/odometry/scan_frontend.h"

namespace rvlio {
namespace scan_queue_test {
namespace {

constexpr TimeNs kMs = 1000000;
constexpr TimeNs kPeriod = 100 * kMs, kSweep = 99 * kMs, kImuPeriod = 5 * kMs;
constexpr TimeNs kT0 = 1000000 * kMs;
constexpr TimeNs kInitEnd = kT0 + 1000 * kMs;  // IMU initialization: the first second

Scan ScanAt(TimeNs start_ns) {
  Scan s;
  s.t_start_ns = start_ns;
  s.t_end_ns = start_ns + kSweep;
  return s;
}

struct Outcome {
  OdometryStats stats;
  std::vector<TimeNs> processed_starts;  // in processing order
};

// `scans` scans, scan i starting at kT0 + i * kPeriod unless `edit` changes
// its start; each is received after the IMU samples up to its nominal end.
// A scan is processed once the IMU covers its end; the state is then at its
// end. Not initialized before kInitEnd.
Outcome Stream(int scans, const std::function<void(int, TimeNs*)>& edit) {
  Outcome o;
  ScanQueue queue;
  TimeNs imu_ns = kT0, state_ns = kInitEnd;
  std::deque<ImuSample> imu;
  auto process_ready = [&] {
    while (queue.FrontReady(imu)) {
      const Scan s = queue.PopFront();
      o.processed_starts.push_back(s.t_start_ns);
      state_ns = s.t_end_ns;
    }
  };
  for (int i = 0; i < scans; ++i) {
    TimeNs start_ns = kT0 + i * kPeriod;
    for (; imu_ns <= start_ns + kSweep; imu_ns += kImuPeriod) {
      queue.NoteImu(imu_ns);
      ImuSample sample;
      sample.t_ns = imu_ns;
      imu.push_back(sample);
    }
    if (edit) edit(i, &start_ns);
    queue.Add(ScanAt(start_ns), imu_ns > kInitEnd, state_ns, &o.stats);
    process_ready();
  }
  queue.DropPastImu(20 * kMs, &o.stats);
  while (!queue.empty()) {
    o.processed_starts.push_back(queue.PopFront().t_start_ns);
  }
  return o;
}

std::vector<TimeNs> NominalStarts(int first, int last_excluded, std::vector<int> skip = {}) {
  std::vector<TimeNs> v;
  for (int i = first; i < last_excluded; ++i)
    if (std::find(skip.begin(), skip.end(), i) == skip.end()) v.push_back(kT0 + i * kPeriod);
  return v;
}

constexpr int kScans = 40;
constexpr int kFirstAfterInit = 10;  // the scans ending after kInitEnd

TEST(ScanQueueStamps, CleanStreamIsTakenWhole) {
  const Outcome o = Stream(kScans, nullptr);
  EXPECT_EQ(o.stats.scans_before_imu, kFirstAfterInit);
  EXPECT_EQ(o.stats.scans_out_of_order, 0);
  EXPECT_EQ(o.processed_starts, NominalStarts(kFirstAfterInit, kScans));
}

// A scan repeating the previous scan's stamp is skipped and counted as out
// of order, wherever it is (at the end of the initialization too, where the
// scan it repeats was not queued).
TEST(ScanQueueStamps, RepeatedStampIsSkippedAsOutOfOrder) {
  for (int k : {kFirstAfterInit, 11, 25, kScans - 1}) {
    SCOPED_TRACE(k);
    const Outcome o = Stream(kScans, [k](int i, TimeNs* start) {
      if (i == k) *start -= kPeriod;
    });
    EXPECT_EQ(o.stats.scans_out_of_order, 1);
    EXPECT_EQ(o.stats.scans_before_imu, kFirstAfterInit);
    EXPECT_EQ(o.processed_starts, NominalStarts(kFirstAfterInit, kScans, {k}));
  }
}

// A stamp 0.5 s ahead (five periods) is the one dropped; the scans after it
// are all taken.
TEST(ScanQueueStamps, StampJumpingAheadCostsOnlyItsScan) {
  for (int k : {kFirstAfterInit, 25, kScans - 7}) {
    SCOPED_TRACE(k);
    const Outcome o = Stream(kScans, [k](int i, TimeNs* start) {
      if (i == k) *start += 500 * kMs;
    });
    EXPECT_EQ(o.stats.scans_out_of_order, 0);
    EXPECT_EQ(o.stats.scans_stamp_ahead, 1);
    EXPECT_EQ(o.stats.scans_before_imu, kFirstAfterInit);
    EXPECT_EQ(o.processed_starts, NominalStarts(kFirstAfterInit, kScans, {k}));
  }
}

// More hostile stamps: two in a row repeating, two in a row ahead, one 0.5 s
// behind, the first scan ahead (before the IMU initialization), the last one
// ahead (nothing follows it: it is past the IMU's end).
TEST(ScanQueueStamps, HostileStampsCostOnlyTheirScans) {
  struct Case {
    const char* name;
    std::function<void(int, TimeNs*)> edit;
    std::vector<int> lost;
    int64_t out_of_order, ahead, after_imu;
  };
  const std::vector<Case> cases = {
      {"two repeats", [](int i, TimeNs* s) { if (i == 20 || i == 21) *s = kT0 + 19 * kPeriod; },
       {20, 21}, 2, 0, 0},
      {"two ahead", [](int i, TimeNs* s) { if (i == 20 || i == 21) *s += 500 * kMs; },
       {20, 21}, 0, 2, 0},
      {"0.5 s behind", [](int i, TimeNs* s) { if (i == 20) *s -= 500 * kMs; }, {20}, 1, 0, 0},
      {"first ahead", [](int i, TimeNs* s) { if (i == 0) *s += 500 * kMs; }, {}, 0, 1, 0},
      {"last ahead", [](int i, TimeNs* s) { if (i == kScans - 1) *s += 500 * kMs; },
       {kScans - 1}, 0, 0, 1},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const Outcome o = Stream(kScans, c.edit);
    EXPECT_EQ(o.stats.scans_out_of_order, c.out_of_order);
    EXPECT_EQ(o.stats.scans_stamp_ahead, c.ahead);
    EXPECT_EQ(o.stats.scans_after_imu, c.after_imu);
    EXPECT_EQ(o.processed_starts, NominalStarts(kFirstAfterInit, kScans, c.lost));
  }
}

// A scan stamped 0.2 s behind, between the two scans before it, is the one
// out of order: the newest scan's stamp agrees with the IMU, which already
// covers it.
TEST(ScanQueueStamps, ScanAgreeingWithTheImuIsKept) {
  const Outcome o = Stream(kScans, [](int i, TimeNs* s) {
    if (i == 21) *s -= 2 * kPeriod;  // arrives after scan 20 with scan 19's stamp
  });
  EXPECT_EQ(o.stats.scans_out_of_order, 1);
  EXPECT_EQ(o.stats.scans_stamp_ahead, 0);
  EXPECT_EQ(o.processed_starts, NominalStarts(kFirstAfterInit, kScans, {21}));
}

}  // namespace
}  // namespace scan_queue_test
}  // namespace rvlio

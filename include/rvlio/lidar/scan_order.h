#pragma once
// The order of scan stamps (docs/robustness.md "Input problems"): each scan
// is judged against the scans received around it and against the IMU.
//
// Scans come in time order. A scan whose end does not follow the newest scan
// taken repeats a stamp or goes back: it is out of order and skipped, unless
// the newest scans are the ones out of place, their stamps having jumped
// ahead (a bit flip in a header stamp): each starts at least a scan period
// after the new scan and ends more than a scan period past the newest IMU
// sample (no other sensor is there yet), and the new scan follows the scan
// taken before them. Then those scans are dropped and the new one taken, so
// that a bad stamp costs its own scan, not the good scans it overtook. The
// decision needs one scan of lookahead: a scan stamped ahead must still be
// droppable when its successor arrives (the odometry's queue holds a scan
// until the IMU covers its end, which a stamp ahead of the IMU is not). The
// scan period is the median of the recent periods between the starts of the
// scans taken (for the first scans: the new scan's sweep).
#include <deque>
#include <limits>
#include <vector>

#include "rvlio/common/time.h"

namespace rvlio {

struct ScanSpan {
  TimeNs start_ns = 0, end_ns = 0;
};

enum class StampVerdict {
  kInOrder,         // take the scan
  kOutOfOrder,      // skip the scan: its end does not follow the newest scan taken
  kNewestWereAhead, // take the scan, and drop the newest scans taken before it (dropped())
};

class ScanStampScreen {
 public:
  static constexpr TimeNs kNoImu = std::numeric_limits<TimeNs>::min();
  static constexpr size_t kRecent = 9;  // scans kept: the period, the longest run dropped

  // Judges the next scan received and remembers it unless it is out of
  // order. imu_end_ns: the newest IMU stamp received (kNoImu: none yet).
  StampVerdict Judge(const ScanSpan& scan, TimeNs imu_end_ns);
  // The scans the last kNewestWereAhead dropped, oldest first.
  const std::vector<ScanSpan>& dropped() const { return dropped_; }

 private:
  // How many of the newest scans jumped ahead of `next` and of the IMU with
  // `next` following the scan before them (0: none, `next` is out of order).
  size_t NewestAhead(const ScanSpan& next, TimeNs imu_end_ns) const;
  // The median period between the starts of recent_[0..count); fallback:
  // `next`'s sweep.
  TimeNs PeriodNs(size_t count, const ScanSpan& next) const;
  void Remember(const ScanSpan& scan);

  std::deque<ScanSpan> recent_;  // the newest scans taken, oldest first
  std::vector<ScanSpan> dropped_;
};

}  // namespace rvlio

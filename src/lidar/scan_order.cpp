#include "rvlio/lidar/scan_order.h"

#include <vector>

#include "rvlio/common/median.h"

namespace rvlio {

StampVerdict ScanStampScreen::Judge(const ScanSpan& scan, TimeNs imu_end_ns) {
  dropped_.clear();
  if (recent_.empty() || scan.end_ns > recent_.back().end_ns) {
    Remember(scan);
    return StampVerdict::kInOrder;
  }
  const size_t ahead = NewestAhead(scan, imu_end_ns);
  if (ahead == 0) return StampVerdict::kOutOfOrder;
  dropped_.assign(recent_.end() - static_cast<ptrdiff_t>(ahead), recent_.end());
  recent_.resize(recent_.size() - ahead);
  Remember(scan);
  return StampVerdict::kNewestWereAhead;
}

// Walks back over the newest scans while each is ahead; the run counts when
// `next` ends after the scan before it (or nothing is before it).
size_t ScanStampScreen::NewestAhead(const ScanSpan& next, TimeNs imu_end_ns) const {
  size_t run = 0;
  while (run < recent_.size()) {
    const size_t i = recent_.size() - 1 - run;
    const ScanSpan& s = recent_[i];
    const TimeNs period_ns = PeriodNs(i, next);
    if (period_ns <= 0) break;
    const bool ahead_of_next = s.start_ns - next.start_ns >= period_ns;
    const bool ahead_of_imu = imu_end_ns == kNoImu || s.end_ns - imu_end_ns > period_ns;
    if (!ahead_of_next || !ahead_of_imu) break;
    ++run;
    if (i == 0 || next.end_ns > recent_[i - 1].end_ns) return run;
  }
  return 0;
}

TimeNs ScanStampScreen::PeriodNs(size_t count, const ScanSpan& next) const {
  std::vector<TimeNs> periods_ns;
  for (size_t i = 1; i < count; ++i) periods_ns.push_back(recent_[i].start_ns - recent_[i - 1].start_ns);
  if (periods_ns.empty()) return next.end_ns - next.start_ns;
  return UpperMedian(periods_ns);
}

void ScanStampScreen::Remember(const ScanSpan& scan) {
  recent_.push_back(scan);
  if (recent_.size() > kRecent) recent_.pop_front();
}

}  // namespace rvlio

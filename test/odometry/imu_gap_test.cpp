// The estimator's IMU-gap count (odometry/scan_frontend.h AcceptImu) uses the
// one configured threshold, imu.max_gap, as the readers do.
#include <deque>
#include <limits>

#include <gtest/gtest.h>

#include "rvlio/common/time.h"
#include "rvlio/odometry/scan_frontend.h"

namespace rvlio {
namespace {

ImuSample Sample(TimeNs t_ns) {
  ImuSample s;
  s.t_ns = t_ns;
  s.acc_imu = Eigen::Vector3d(0.0, 0.0, 9.81);
  s.gyro_imu = Eigen::Vector3d::Zero();
  return s;
}

// Samples at 200 Hz with one gap of gap_ms; the count of AcceptImu.
int64_t GapsCounted(TimeNs gap_ms, double max_gap_s) {
  OdometryStats stats;
  std::deque<ImuSample> buffer;
  TimeNs t_ns = 0;
  for (int i = 0; i < 40; ++i) {
    t_ns += (i == 20 ? gap_ms : 5) * 1000000;
    const ImuSample s = Sample(t_ns);
    if (AcceptImu(s, buffer, SecondsToNs(max_gap_s), &stats)) buffer.push_back(s);
  }
  return stats.imu_gaps_over_scan;
}

TEST(ImuGap, CountedAgainstTheConfiguredMaxGap) {
  EXPECT_EQ(GapsCounted(300, 0.1), 1);  // the default imu.max_gap
  EXPECT_EQ(GapsCounted(300, 0.5), 0);  // a longer threshold: not a gap
  EXPECT_EQ(GapsCounted(100, 0.1), 0);  // exactly max_gap is not longer than it
  EXPECT_EQ(GapsCounted(101, 0.1), 1);
}

TEST(ImuGap, NonFiniteSampleIsRefusedAndCounted) {
  OdometryStats stats;
  std::deque<ImuSample> buffer;
  ImuSample s = Sample(5000000);
  s.gyro_imu.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(AcceptImu(s, buffer, SecondsToNs(0.1), &stats));
  EXPECT_EQ(stats.imu_non_finite, 1);
  EXPECT_EQ(stats.imu_gaps_over_scan, 0);
}

}  // namespace
}  // namespace rvlio

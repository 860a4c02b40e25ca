// The time-offset report of both backends (odometry/odometry.h): the note of
// summary.json and the run's warning are made from it, so they say what was
// measured and agree with its fields.
#include <string>

#include <gtest/gtest.h>

#include "rvlio/odometry/odometry.h"

namespace rvlio {
namespace time_offset_report_test {
namespace {

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TimeOffsetReport Measured(double excited_s, double scans_s, double rate_spread, double v_spread) {
  TimeOffsetReport r;
  r.enabled = true;
  r.estimate_s = 0.0302;
  r.std_s = 6e-5;
  r.bound_s = 0.2;
  r.trust_std_s = 0.002;
  r.excited_s = excited_s;
  r.excited = excited_s >= TimeOffsetExcitation::kMinExcitedSeconds;
  r.scans_s = scans_s;
  r.max_rate_spread_rad_s = rate_spread;
  r.max_velocity_spread_m_s = v_spread;
  r.trustworthy = r.excited;
  return r;
}

// Item: a swaying flight with 4.5 s of excited scans (< 5 s) was noted as
// "the motion never excited the time offset (hover or constant velocity)";
// the note now states the seconds measured and the threshold, and names a
// hover only when the motion never reached the excitation thresholds.
TEST(TimeOffsetNote, SaysWhatWasMeasuredNotACauseThatDidNotHappen) {
  const std::string short_flight = TimeOffsetNote(Measured(4.5, 6.8, 0.83, 0.37));
  EXPECT_FALSE(Contains(short_flight, "never excited")) << short_flight;
  EXPECT_FALSE(Contains(short_flight, "hover")) << short_flight;
  EXPECT_TRUE(Contains(short_flight, "4.5 s of the 6.8 s of scans excited the offset (needed: 5 s"))
      << short_flight;
  EXPECT_TRUE(Contains(short_flight, "0.83 rad/s")) << short_flight;

  const std::string hover = TimeOffsetNote(Measured(0.0, 6.8, 0.01, 0.02));
  EXPECT_TRUE(Contains(hover, "never excited")) << hover;
  EXPECT_TRUE(Contains(hover, "at most 0.010 rad/s")) << hover;

  const std::string good = TimeOffsetNote(Measured(16.5, 19.8, 0.83, 0.37));
  EXPECT_TRUE(Contains(good, "put estimate_s in lidar.time_offset: 16.5 s of the 19.8 s")) << good;
}

// Item: the estimate reached the bound and came back: summary.json said
// at_bound true while estimate_s was -0.0425 and the warning said it was
// held at the bound. at_bound is now the final estimate's; the warning and
// the note give the scans at the bound and the final value.
TEST(TimeOffsetNote, BoundWarningAgreesWithTheReport) {
  LidarOptions lidar;
  lidar.estimate_time_offset = true;
  lidar.time_offset_max = 0.2;
  const TimeOffsetExcitation excitation;
  TimeOffsetReport r;
  const TimeNs t0 = 1700000000000000000;
  UpdateTimeOffsetReport(excitation, lidar, 0.01, 0.01, false, t0, &r);
  EXPECT_TRUE(TimeOffsetWarnings(r).empty());
  UpdateTimeOffsetReport(excitation, lidar, 0.2, 0.01, true, t0 + 100000000, &r);
  UpdateTimeOffsetReport(excitation, lidar, 0.2, 0.01, true, t0 + 200000000, &r);
  ASSERT_EQ(TimeOffsetWarnings(r).size(), 1u);
  EXPECT_TRUE(r.at_bound);
  EXPECT_TRUE(Contains(TimeOffsetWarnings(r)[0], "is held at lidar.time_offset_max (+0.2 s)"));
  UpdateTimeOffsetReport(excitation, lidar, -0.0425, 0.001, false, t0 + 300000000, &r);
  EXPECT_FALSE(r.at_bound);
  EXPECT_EQ(r.bound_scans, 2);
  EXPECT_EQ(r.first_bound_t_ns, t0 + 100000000);
  const std::vector<std::string> w = TimeOffsetWarnings(r);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_TRUE(Contains(w[0], "reached lidar.time_offset_max (0.2 s) on 2 scans")) << w[0];
  EXPECT_TRUE(Contains(w[0], "and ended at -0.0425 s")) << w[0];
  EXPECT_FALSE(Contains(w[0], "held")) << w[0];
  EXPECT_TRUE(Contains(TimeOffsetNote(r), "and ended at -0.0425 s")) << TimeOffsetNote(r);
}

}  // namespace
}  // namespace time_offset_report_test
}  // namespace rvlio

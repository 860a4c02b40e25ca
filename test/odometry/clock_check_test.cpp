// The offline clock check's lag search (odometry/clock_check.h) on
// synthetic samples: an analytic swaying gyro rate, and LiDAR rotation
// samples that measure it through weighted shares of the sweep, as a
// scan-to-scan registration of undeskewed scans does.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/odometry/clock_check.h"

namespace rvlio {
namespace clock_check_test {
namespace {

constexpr TimeNs kMs = 1000000;
constexpr TimeNs kT0 = 1000000 * kMs;
constexpr TimeNs kScanPeriod = 100 * kMs;
constexpr int kShares = 10;

// Sway about three axes (rad/s), 0.6 rad/s at 1, 1.37 and 0.71 Hz.
struct Sway {
  double start_s = 0.0;  // at rest before
  Eigen::Vector3d f_hz{1.0, 1.37, 0.71}, phase{0.3, 1.1, 2.0};
  double amplitude = 0.6;
  Eigen::Vector3d Rate(double t_s) const {
    if (t_s < start_s) return Eigen::Vector3d::Zero();
    Eigen::Vector3d w;
    for (int i = 0; i < 3; ++i) w[i] = amplitude * std::sin(2 * M_PI * f_hz[i] * t_s + phase[i]);
    return w;
  }
  // The exact mean rate over [a_s, b_s].
  Eigen::Vector3d Mean(double a_s, double b_s) const { return (Integral(b_s) - Integral(a_s)) / (b_s - a_s); }
  // The rotation from start_s to t_s.
  Eigen::Vector3d Integral(double t_s) const {
    const double t = std::max(t_s, start_s);
    Eigen::Vector3d c;
    for (int i = 0; i < 3; ++i) {
      const double k = 2 * M_PI * f_hz[i];
      c[i] = -amplitude / k * (std::cos(k * t + phase[i]) - std::cos(k * start_s + phase[i]));
    }
    return c;
  }
};

double Seconds(TimeNs t_ns) { return NsToSeconds(t_ns - kT0); }

std::vector<ImuSample> Gyro(const Sway& sway, double duration_s) {
  std::vector<ImuSample> imu;
  for (TimeNs t = kT0; t <= kT0 + SecondsToNs(duration_s); t += 5 * kMs) {
    ImuSample s;
    s.t_ns = t;
    s.gyro_imu = sway.Rate(Seconds(t));
    imu.push_back(s);
  }
  return imu;
}

struct Samples {
  std::vector<LidarRateSample> shares;  // the measurement model of the check
  std::vector<LidarRateSample> mid;     // the same rates taken between the scans' mid-times
};

// Scan k sweeps [t_k, t_k + 99 ms] (LiDAR clock, t_imu = t_lidar + lag_s);
// most of the registration's information comes from the start of the sweep
// (share weights falling off as exp(-b / 2)). `noise` rad/s per axis.
Samples Make(const Sway& sway, double duration_s, double lag_s, double noise, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01;
  std::vector<double> w(kShares);
  double sum = 0.0;
  for (int b = 0; b < kShares; ++b) sum += w[b] = std::exp(-b / 2.0);
  Samples out;
  const double margin_s = 0.3;  // the search range needs gyro around each sample
  for (TimeNs t = kT0 + SecondsToNs(margin_s) + kScanPeriod;
       t + kScanPeriod < kT0 + SecondsToNs(duration_s - margin_s); t += kScanPeriod) {
    LidarRateSample s;
    s.period_ns = kScanPeriod;
    for (int b = 0; b < kShares; ++b) {
      RotationSamplePart p;
      p.t1_ns = t + (2 * b + 1) * 99 * kMs / (2 * kShares);
      p.t0_ns = p.t1_ns - kScanPeriod;
      p.weight = Eigen::Matrix3d::Identity() * (w[b] / sum);
      s.rate_imu += p.weight * sway.Mean(Seconds(p.t0_ns) + lag_s, Seconds(p.t1_ns) + lag_s);
      s.parts.push_back(p);
    }
    for (int i = 0; i < 3; ++i) s.rate_imu[i] += noise * n01(rng);
    LidarRateSample m = s;
    m.parts = {RotationSamplePart{t - kScanPeriod + 99 * kMs / 2, t + 99 * kMs / 2,
                                  Eigen::Matrix3d::Identity()}};
    out.shares.push_back(s);
    out.mid.push_back(m);
  }
  return out;
}

// The cause of the calibrate-time bias on short swaying flights: taken
// between the scans' mid-times, samples that measure the start of the sweep
// give a lag off by milliseconds; with the shares it is exact.
TEST(ClockCheck, SharesFindTheLagTheMidTimesMiss) {
  const Sway sway;  // from the start (a rate step would cost the gyro's trapezoids 0.1 ms)
  const double lag_s = 0.03;
  const std::vector<ImuSample> imu = Gyro(sway, 8.0);
  const Samples s = Make(sway, 8.0, lag_s, 0.0, 1);
  const ClockCheckResult shares = EstimateClockLag(s.shares, imu, ClockCheckOptions());
  EXPECT_EQ(shares.verdict, ClockVerdict::kJudged);
  EXPECT_NEAR(shares.lag_s, lag_s, 5e-5);
  const ClockCheckResult mid = EstimateClockLag(s.mid, imu, ClockCheckOptions());
  EXPECT_GT(std::abs(mid.lag_s - lag_s), 0.01);
}

// With registration noise the 1-sigma covers the error, over seeds.
TEST(ClockCheck, OneSigmaCoversTheErrorWithNoise) {
  Sway sway;
  sway.start_s = 3.0;
  const std::vector<ImuSample> imu = Gyro(sway, 8.0);
  int within_2_sigma = 0;
  constexpr int kSeeds = 20;
  for (uint32_t seed = 1; seed <= kSeeds; ++seed) {
    const Samples s = Make(sway, 8.0, -0.03, 0.02, seed);
    const ClockCheckResult r = EstimateClockLag(s.shares, imu, ClockCheckOptions());
    ASSERT_EQ(r.verdict, ClockVerdict::kJudged) << seed;
    within_2_sigma += std::abs(r.lag_s + 0.03) <= 2.0 * r.std_s ? 1 : 0;
  }
  EXPECT_GE(within_2_sigma, 17);  // 95 % expected
}

// What the recording cannot judge: too short, no rotation.
TEST(ClockCheck, ShortOrStillRecordingsAreNotJudged) {
  Sway moving;  // sways from the start
  const std::vector<ImuSample> imu2 = Gyro(moving, 2.0);
  const ClockCheckResult short_flight =
      EstimateClockLag(Make(moving, 2.0, 0.03, 0.0, 1).shares, imu2, ClockCheckOptions());
  EXPECT_EQ(short_flight.verdict, ClockVerdict::kTooShort);
  EXPECT_LT(short_flight.moving_s, 3.0);

  Sway still;
  still.start_s = 100.0;
  const std::vector<ImuSample> imu8 = Gyro(still, 8.0);
  const ClockCheckResult at_rest =
      EstimateClockLag(Make(still, 8.0, 0.03, 0.001, 1).shares, imu8, ClockCheckOptions());
  EXPECT_EQ(at_rest.verdict, ClockVerdict::kNotEnoughRotation);
}

}  // namespace
}  // namespace clock_check_test
}  // namespace rvlio

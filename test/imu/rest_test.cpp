// FindRestPeriods: still spans of a synthetic IMU signal between vibrating
// ones (imu/rest.h).
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/imu/rest.h"

namespace rvlio {
namespace {

constexpr double kRate = 200.0;

// Samples from t0 for `seconds`: noise like the simulator's MEMS IMU, plus an
// 87 Hz vibration (0.3 m/s^2, 0.02 rad/s) when `vibrating`.
void Append(double seconds, bool vibrating, std::mt19937* rng, std::vector<ImuSample>* imu) {
  std::normal_distribution<double> n(0.0, 1.0);
  const TimeNs t0 = imu->empty() ? 1000000000 : imu->back().t_ns + SecondsToNs(1.0 / kRate);
  const int count = static_cast<int>(seconds * kRate);
  for (int i = 0; i < count; ++i) {
    ImuSample s;
    s.t_ns = t0 + SecondsToNs(i / kRate);
    const double v = vibrating ? std::sin(2 * M_PI * 87.0 * i / kRate) : 0.0;
    s.acc_imu = Eigen::Vector3d(0.03 * n(*rng), 0.03 * n(*rng), 9.81 + 0.03 * n(*rng) + 0.3 * v);
    s.gyro_imu = Eigen::Vector3d(0.003 * n(*rng), 0.003 * n(*rng), 0.003 * n(*rng) + 0.02 * v);
    imu->push_back(s);
  }
}

TEST(RestPeriods, FindsTheStillSpansBetweenVibratingOnes) {
  std::mt19937 rng(5);
  std::vector<ImuSample> imu;
  Append(3.0, false, &rng, &imu);  // rest 1: 0 .. 3 s
  Append(10.0, true, &rng, &imu);
  Append(4.0, false, &rng, &imu);  // rest 2: 13 .. 17 s
  Append(1.0, true, &rng, &imu);
  Append(1.0, false, &rng, &imu);  // too short
  Append(5.0, true, &rng, &imu);
  Append(2.5, false, &rng, &imu);  // rest 3 at the end
  RestDetectorOptions o;
  const std::vector<RestPeriod> rests = FindRestPeriods(imu, o);
  ASSERT_EQ(rests.size(), 3u);
  const double t0 = NsToSeconds(imu.front().t_ns);
  // Each rest's ends lie within half a window of the true ones.
  EXPECT_NEAR(NsToSeconds(rests[0].t_begin_ns) - t0, 0.0, 0.3);
  EXPECT_NEAR(NsToSeconds(rests[0].t_end_ns) - t0, 3.0, 0.3);
  EXPECT_NEAR(NsToSeconds(rests[1].t_begin_ns) - t0, 13.0, 0.3);
  EXPECT_NEAR(NsToSeconds(rests[1].t_end_ns) - t0, 17.0, 0.3);
  EXPECT_NEAR(NsToSeconds(rests[2].t_end_ns) - t0, 26.5, 0.3);
  // A longer minimum drops the shorter rests.
  o.min_duration_s = 3.5;
  EXPECT_EQ(FindRestPeriods(imu, o).size(), 1u);
}

TEST(RestPeriods, AnImuGapEndsARest) {
  std::mt19937 rng(6);
  std::vector<ImuSample> imu;
  Append(3.0, false, &rng, &imu);
  std::vector<ImuSample> later;
  Append(3.0, false, &rng, &later);
  for (ImuSample& s : later) s.t_ns += SecondsToNs(5.0);
  imu.insert(imu.end(), later.begin(), later.end());
  EXPECT_EQ(FindRestPeriods(imu, RestDetectorOptions()).size(), 2u);
  EXPECT_TRUE(FindRestPeriods({}, RestDetectorOptions()).empty());
}

}  // namespace
}  // namespace rvlio

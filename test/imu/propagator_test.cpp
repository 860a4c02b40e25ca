// ImuPropagator: the IMU-rate state between two estimates (imu/propagator.h).
#include <gtest/gtest.h>

#include "rvlio/imu/propagator.h"

namespace rvlio {
namespace {

constexpr TimeNs kDtNs = 5000000;  // 200 Hz

// A level IMU accelerating at 1 m/s^2 along x while turning at 0.1 rad/s about z.
ImuSample Sample(int i) {
  ImuSample s;
  s.t_ns = i * kDtNs;
  s.acc_imu = Eigen::Vector3d(1.0, 0.0, 9.81);
  s.gyro_imu = Eigen::Vector3d(0.0, 0.0, 0.1);
  return s;
}

ImuEstimate EstimateAt(TimeNs t_ns) {
  ImuEstimate e;
  e.state.t_ns = t_ns;
  e.state.v_world_imu = Eigen::Vector3d(2.0, 0.0, 0.0);
  return e;
}

TEST(ImuPropagator, NothingBeforeAnEstimate) {
  ImuPropagator p(SecondsToNs(2.0));
  EXPECT_FALSE(p.Add(Sample(0)).has_value());
  EXPECT_FALSE(p.has_estimate());
}

// Each new sample advances the state by the estimators' own interval scheme.
TEST(ImuPropagator, StepsByIntegrateInterval) {
  ImuPropagator p(SecondsToNs(2.0));
  p.Add(Sample(0));
  const ImuEstimate e = EstimateAt(0);
  p.SetEstimate(e);
  ImuKinematics want = e.state;
  for (int i = 1; i <= 40; ++i) {
    want = IntegrateInterval(want, Sample(i - 1), Sample(i), e.bg_imu, e.ba_imu, e.g_world);
    const std::optional<ImuKinematics> got = p.Add(Sample(i));
    ASSERT_TRUE(got.has_value());
    EXPECT_EQ(got->t_ns, Sample(i).t_ns);
    EXPECT_LT((got->p_world_imu - want.p_world_imu).norm(), 1e-12);
    EXPECT_LT((got->R_world_imu - want.R_world_imu).norm(), 1e-12);
  }
  // 0.2 s at 2 m/s plus 1 m/s^2 (turning slowly): about 0.42 m along x.
  EXPECT_NEAR(want.p_world_imu.x(), 0.42, 0.01);
}

// An estimate that arrives late (its scan ended before the newest sample) is
// carried forward over the samples received since.
TEST(ImuPropagator, LateEstimateCarriedOverKeptSamples) {
  ImuPropagator direct(SecondsToNs(2.0)), late(SecondsToNs(2.0));
  direct.Add(Sample(0));
  late.Add(Sample(0));
  direct.SetEstimate(EstimateAt(0));
  std::optional<ImuKinematics> want, got;
  for (int i = 1; i <= 20; ++i) {
    want = direct.Add(Sample(i));
    late.Add(Sample(i));
  }
  late.SetEstimate(EstimateAt(0));
  want = direct.Add(Sample(21));
  got = late.Add(Sample(21));
  ASSERT_TRUE(want && got);
  EXPECT_LT((got->p_world_imu - want->p_world_imu).norm(), 1e-12);
  EXPECT_LT((got->v_world_imu - want->v_world_imu).norm(), 1e-12);
  // An older estimate than the current one is ignored.
  late.SetEstimate(EstimateAt(-kDtNs));
  EXPECT_LT((late.Add(Sample(22))->p_world_imu - direct.Add(Sample(22))->p_world_imu).norm(), 1e-12);
}

TEST(ImuPropagator, KeepsOnlyRecentSamplesAndCoversSpans) {
  ImuPropagator p(SecondsToNs(0.1));
  for (int i = 0; i <= 100; ++i) p.Add(Sample(i));
  EXPECT_LE(p.samples().size(), 22u);
  const std::vector<ImuSample> c = p.Covering(Sample(95).t_ns + 1, Sample(97).t_ns);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.front().t_ns, Sample(95).t_ns);
  EXPECT_EQ(c.back().t_ns, Sample(97).t_ns);
  EXPECT_FALSE(p.Add(Sample(100)).has_value());  // a repeated stamp is ignored
}

}  // namespace
}  // namespace rvlio

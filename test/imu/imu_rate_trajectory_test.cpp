// The IMU-rate trajectory between states (imu/imu_rate_trajectory.h): on a
// motion of constant world acceleration and constant body rate (which the
// integration scheme follows exactly), the poses at the states are the
// states and those between them follow the motion; the two joins; the
// propagator's poses; stamps, order and streaming.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/imu/imu_rate_trajectory.h"
#include "rvlio/imu/propagator.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace imu_rate_test {  // named: the test folder compiles as one unit (unity build)

using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr TimeNs kImuNs = 5000000;     // 200 Hz
constexpr TimeNs kScanNs = 100000000;  // 10 Hz
const Vector3d kGravity(0.0, 0.0, -9.81);
const Vector3d kAccWorld(0.8, -0.3, 0.2);  // m/s^2
const Vector3d kRateImu(0.05, -0.1, 0.4);  // rad/s
const Vector3d kV0(2.0, 0.5, -0.1);        // m/s
const Vector3d kP0(10.0, -4.0, 1.5);       // m
const Matrix3d kR0 = so3::Exp(Vector3d(0.1, -0.2, 0.7));

// The true state at t_ns: R0 Exp(w t), p0 + v0 t + a t^2 / 2.
ImuKinematics Truth(TimeNs t_ns) {
  const double t = NsToSeconds(t_ns);
  ImuKinematics x;
  x.t_ns = t_ns;
  x.R_world_imu = kR0 * so3::Exp(kRateImu * t);
  x.p_world_imu = kP0 + kV0 * t + 0.5 * kAccWorld * t * t;
  x.v_world_imu = kV0 + kAccWorld * t;
  return x;
}

// Ideal samples every kImuNs from first_ns to last_ns (offset by offset_ns).
std::vector<ImuSample> Samples(TimeNs first_ns, TimeNs last_ns, TimeNs offset_ns = 0) {
  std::vector<ImuSample> out;
  for (TimeNs t = first_ns + offset_ns; t <= last_ns; t += kImuNs) {
    ImuSample s;
    s.t_ns = t;
    s.acc_imu = Truth(t).R_world_imu.transpose() * (kAccWorld - kGravity);
    s.gyro_imu = kRateImu;
    out.push_back(s);
  }
  return out;
}

ImuEstimate State(TimeNs t_ns) {
  ImuEstimate e;
  e.state = Truth(t_ns);
  e.g_world = kGravity;
  return e;
}

std::vector<ImuEstimate> ScanStates(int scans, TimeNs offset_ns = 0) {
  std::vector<ImuEstimate> states;
  for (int k = 0; k < scans; ++k) states.push_back(State(offset_ns + k * kScanNs));
  return states;
}

double PositionError(const StampedPose& p, const ImuKinematics& x) {
  return (p.p_world_imu - x.p_world_imu).norm();
}
double RotationError(const StampedPose& p, const Matrix3d& R) {
  return so3::Log(p.q_world_imu.toRotationMatrix().transpose() * R).norm();
}

TEST(ImuRateTrajectory, FollowsAConstantAccelerationAndRotationAndHitsEveryState) {
  // Scan ends 2.5 ms off the IMU grid: states between samples.
  const std::vector<ImuEstimate> states = ScanStates(11, kImuNs / 2);
  const std::vector<ImuSample> samples = Samples(-kImuNs, 11 * kScanNs);
  for (ImuRateJoin join : {ImuRateJoin::kPropagate, ImuRateJoin::kSpread}) {
    const Trajectory poses = ImuRatePoses(states, samples, join);
    // 1 s at 200 Hz: 200 samples inside, plus the 11 states.
    ASSERT_EQ(poses.size(), 211u);
    size_t k = 0;
    for (size_t i = 0; i < poses.size(); ++i) {
      if (i > 0) {
        ASSERT_GT(poses[i].t_ns, poses[i - 1].t_ns);
      }
      const ImuKinematics want = Truth(poses[i].t_ns);
      EXPECT_LT(PositionError(poses[i], want), 1e-9) << i;
      EXPECT_LT(RotationError(poses[i], want.R_world_imu), 1e-9) << i;
      if (k < states.size() && poses[i].t_ns == states[k].state.t_ns) {
        EXPECT_EQ(poses[i].p_world_imu, states[k].state.p_world_imu);
        ++k;
      } else {
        EXPECT_EQ((poses[i].t_ns + kImuNs) % kImuNs, 0) << "not a sample stamp: " << poses[i].t_ns;
      }
    }
    EXPECT_EQ(k, states.size());
    EXPECT_EQ(poses.front().t_ns, states.front().state.t_ns);
    EXPECT_EQ(poses.back().t_ns, states.back().state.t_ns);
  }
}

// A state at a sample's stamp gives that stamp one pose, the state's.
TEST(ImuRateTrajectory, StatesOnSampleStampsAreNotRepeated) {
  const Trajectory poses =
      ImuRatePoses(ScanStates(3), Samples(0, 3 * kScanNs), ImuRateJoin::kPropagate);
  ASSERT_EQ(poses.size(), 41u);  // 0 .. 200 ms at 5 ms
  for (size_t i = 0; i < poses.size(); ++i)
    EXPECT_EQ(poses[i].t_ns, static_cast<TimeNs>(i) * kImuNs);
}

// A later state off the forward integration (here 3 cm and 0.5 deg): the
// propagated poses step onto it at its stamp, the spread ones reach it
// continuously, the mismatch growing linearly in time.
TEST(ImuRateTrajectory, TheJoinsPropagateOrSpreadTheEndMismatch) {
  const ImuEstimate a = State(0);
  ImuEstimate b = State(kScanNs);
  const Vector3d dp(0.03, 0.0, -0.01);
  const Vector3d dtheta(0.0, 0.0, 0.5 * M_PI / 180.0);
  b.state.p_world_imu += dp;
  b.state.R_world_imu = so3::Exp(dtheta) * b.state.R_world_imu;
  const std::vector<ImuSample> samples = Samples(0, 2 * kScanNs);
  const std::vector<ImuKinematics> propagated =
      ImuRateBetween(a, b, samples, ImuRateJoin::kPropagate);
  const std::vector<ImuKinematics> spread = ImuRateBetween(a, b, samples, ImuRateJoin::kSpread);
  ASSERT_EQ(propagated.size(), 20u);  // 19 samples inside, then b
  ASSERT_EQ(spread.size(), 20u);
  for (size_t i = 0; i + 1 < spread.size(); ++i) {
    const ImuKinematics truth = Truth(spread[i].t_ns);
    const double s = NsToSeconds(spread[i].t_ns) / NsToSeconds(kScanNs);
    EXPECT_LT((propagated[i].p_world_imu - truth.p_world_imu).norm(), 1e-9);
    EXPECT_LT((spread[i].p_world_imu - (truth.p_world_imu + s * dp)).norm(), 1e-9);
    EXPECT_LT((so3::Log(spread[i].R_world_imu * truth.R_world_imu.transpose()) - s * dtheta).norm(),
              1e-9);
  }
  for (const auto* states : {&propagated, &spread}) {
    EXPECT_EQ(states->back().t_ns, b.state.t_ns);
    EXPECT_EQ(states->back().p_world_imu, b.state.p_world_imu);
    EXPECT_EQ(states->back().R_world_imu, b.state.R_world_imu);
  }
  // The last step: the whole mismatch for the propagated poses, 1/20 of it spread.
  EXPECT_NEAR((propagated[19].p_world_imu - propagated[18].p_world_imu -
               (Truth(kScanNs).p_world_imu - Truth(19 * kImuNs).p_world_imu))
                  .norm(),
              dp.norm(), 1e-9);
  EXPECT_NEAR((spread[19].p_world_imu - spread[18].p_world_imu -
               (Truth(kScanNs).p_world_imu - Truth(19 * kImuNs).p_world_imu))
                  .norm(),
              dp.norm() / 20.0, 1e-9);
}

// kPropagate gives what `rvlio live`'s propagator publishes when each
// estimate is set before the samples after it arrive (biased estimates).
TEST(ImuRateTrajectory, PropagatedPosesAreThePropagatorsOnes) {
  std::vector<ImuEstimate> states = ScanStates(4, 3 * kImuNs / 2);
  for (ImuEstimate& e : states) {
    e.bg_imu = Vector3d(0.002, -0.001, 0.003);
    e.ba_imu = Vector3d(0.05, 0.02, -0.04);
    e.state.v_world_imu += Vector3d(0.1, 0.0, 0.0);
  }
  const std::vector<ImuSample> samples = Samples(0, 4 * kScanNs);
  const Trajectory poses = ImuRatePoses(states, samples, ImuRateJoin::kPropagate);
  ImuPropagator propagator(SecondsToNs(1.0));
  size_t next_state = 0, checked = 0;
  for (const ImuSample& s : samples) {
    std::optional<ImuKinematics> live = propagator.Add(s);
    if (next_state < states.size() && states[next_state].state.t_ns < s.t_ns) {
      propagator.SetEstimate(states[next_state++]);  // carries it to s
      live = propagator.Add(s);                      // repeated: ignored
      EXPECT_FALSE(live.has_value());
      continue;  // the carried state is checked at the next sample
    }
    if (!live || s.t_ns > states.back().state.t_ns) continue;
    for (const StampedPose& p : poses) {
      if (p.t_ns != s.t_ns) continue;
      EXPECT_LT(PositionError(p, *live), 1e-12) << s.t_ns;
      EXPECT_LT(RotationError(p, live->R_world_imu), 1e-12) << s.t_ns;
      ++checked;
    }
  }
  EXPECT_GT(checked, 50u);
}

// Streaming (states arriving after the samples that cover them, stray
// samples among them) gives the trajectory of the whole call.
TEST(ImuRateTrajectory, StreamingEqualsTheWholeAndIgnoresStraySamplesAndStates) {
  const std::vector<ImuEstimate> states = ScanStates(6, kImuNs / 3);
  const std::vector<ImuSample> samples = Samples(-2 * kImuNs, 6 * kScanNs);
  const Trajectory whole = ImuRatePoses(states, samples, ImuRateJoin::kSpread);
  ImuRateTrajectory stream(ImuRateJoin::kSpread);
  size_t next_state = 0;
  for (const ImuSample& s : samples) {
    stream.AddImu(s);
    stream.AddImu(s);  // repeated
    ImuSample bad = s;
    bad.acc_imu.x() = NAN;
    bad.t_ns += 1;
    stream.AddImu(bad);  // not finite
    // Each state once a sample 10 ms after it is in (as a run's results).
    while (next_state < states.size() && states[next_state].state.t_ns + 2 * kImuNs <= s.t_ns) {
      stream.AddEstimate(states[next_state]);
      stream.AddEstimate(states[next_state]);  // repeated: ignored
      ++next_state;
    }
  }
  ASSERT_EQ(next_state, states.size());
  ASSERT_EQ(stream.poses().size(), whole.size());
  for (size_t i = 0; i < whole.size(); ++i) {
    EXPECT_EQ(stream.poses()[i].t_ns, whole[i].t_ns);
    EXPECT_LT((stream.poses()[i].p_world_imu - whole[i].p_world_imu).norm(), 1e-12);
  }
}

}  // namespace imu_rate_test
}  // namespace rvlio

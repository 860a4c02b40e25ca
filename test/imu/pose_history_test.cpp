// ImuPoseHistory: the one source of deskew poses of every backend. Its
// integrated samples reproduce the integrator's states at every knot, forward
// (smoother prediction) and backward (refine), and interpolate between them.
#include <cmath>

#include <gtest/gtest.h>

#include "rvlio/imu/pose_history.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

const Vector3d kGravityHistory(0.0, 0.0, -9.81);

// A turning, accelerating signal sampled every 5 ms (biases included).
std::vector<ImuSample> Signal(TimeNs t0_ns, TimeNs t1_ns) {
  std::vector<ImuSample> imu;
  for (TimeNs t = t0_ns; t <= t1_ns; t += 5000000) {
    const double s = NsToSeconds(t);
    ImuSample m;
    m.t_ns = t;
    m.gyro_imu = Vector3d(0.2 * std::sin(3.0 * s), -0.1, 0.6 + 0.3 * std::cos(2.0 * s));
    m.acc_imu = Vector3d(0.5 * std::cos(4.0 * s), 0.3, 9.6 + 0.2 * std::sin(s));
    imu.push_back(m);
  }
  return imu;
}

ImuKinematics Start(TimeNs t_ns) {
  ImuKinematics x;
  x.t_ns = t_ns;
  x.R_world_imu = so3::Exp(Vector3d(0.1, -0.2, 0.7));
  x.p_world_imu = Vector3d(1.0, 2.0, 0.5);
  x.v_world_imu = Vector3d(1.5, -0.3, 0.1);
  return x;
}

void ExpectSamePose(const Pose3& a, const ImuKinematics& b, double tol) {
  EXPECT_LT((a.t - b.p_world_imu).norm(), tol);
  EXPECT_LT(so3::Log(a.R.transpose() * b.R_world_imu).norm(), tol);
}

const Vector3d kBg(0.01, -0.02, 0.005), kBa(0.05, -0.03, 0.02);

TEST(ImuPoseHistory, ForwardIntegrationReproducesEveryKnotAndPredictsTheEnd) {
  const std::vector<ImuSample> imu = Signal(0, 200000000);
  const TimeNs t0 = 12000000, t1 = 113000000;  // off the sample grid
  const ImuPoseHistory h = ImuPoseHistory::Integrate(Start(t0), imu, t1, kBg, kBa, kGravityHistory);
  const std::vector<ImuKinematics> knots =
      IntegrateTrajectory(Start(t0), imu, t1, kBg, kBa, kGravityHistory);
  ASSERT_EQ(h.samples().size(), knots.size());
  for (size_t i = 0; i < knots.size(); ++i) {
    EXPECT_EQ(h.samples()[i].t_ns, knots[i].t_ns);
    ExpectSamePose(h.PoseAt(knots[i].t_ns), knots[i], 1e-9);
  }
  const ImuKinematics newest = h.Newest();
  EXPECT_EQ(newest.t_ns, t1);
  EXPECT_EQ(newest.p_world_imu, knots.back().p_world_imu);
  EXPECT_EQ(newest.v_world_imu, knots.back().v_world_imu);
}

TEST(ImuPoseHistory, BackwardIntegrationIsSortedAndAgreesWithForward) {
  const std::vector<ImuSample> imu = Signal(0, 200000000);
  const TimeNs t0 = 12000000, t1 = 113000000;
  const ImuPoseHistory fwd = ImuPoseHistory::Integrate(Start(t0), imu, t1, kBg, kBa, kGravityHistory);
  const ImuPoseHistory bwd = ImuPoseHistory::Integrate(fwd.Newest(), imu, t0, kBg, kBa, kGravityHistory);
  ASSERT_EQ(bwd.samples().size(), fwd.samples().size());
  EXPECT_EQ(bwd.samples().front().t_ns, t0);
  EXPECT_EQ(bwd.samples().back().t_ns, t1);
  for (size_t i = 1; i < bwd.samples().size(); ++i)
    EXPECT_GT(bwd.samples()[i].t_ns, bwd.samples()[i - 1].t_ns);
  // Between knots too (points of a scan): the same motion either way.
  for (TimeNs t = t0; t <= t1; t += 1700000) {
    const Pose3 a = fwd.PoseAt(t), b = bwd.PoseAt(t);
    EXPECT_LT((a.t - b.t).norm(), 1e-9) << t;
    EXPECT_LT(so3::Log(a.R.transpose() * b.R).norm(), 1e-9) << t;
  }
  ExpectSamePose(bwd.PoseAt(t0), Start(t0), 1e-9);
}

TEST(ImuPoseHistory, AppendedStatesAreHeldMotionsInTimeOrder) {
  ImuPoseHistory h;
  EXPECT_TRUE(h.empty());
  ImuPoseSample s;
  s.t_ns = 1000000000;
  s.v_world_imu = Vector3d(1.0, 0.0, 0.0);
  s.acc_world = Vector3d(0.0, 2.0, 0.0);
  s.gyro_imu = Vector3d(0.0, 0.0, 0.5);
  h.Append(s);
  ImuPoseSample later = s;
  later.t_ns += 100000000;
  later.p_world_imu = Vector3d(5.0, 5.0, 5.0);
  h.Append(later);
  const Pose3 mid = h.PoseAt(s.t_ns + 50000000);  // from the first sample: 0.05 s
  EXPECT_LT((mid.t - Vector3d(0.05, 0.5 * 2.0 * 0.05 * 0.05, 0.0)).norm(), 1e-12);
  EXPECT_NEAR(so3::Log(mid.R).z(), 0.5 * 0.05, 1e-12);
  EXPECT_EQ(h.Newest().p_world_imu, later.p_world_imu);
  h.Clear();
  EXPECT_TRUE(h.empty());
}

}  // namespace
}  // namespace rvlio

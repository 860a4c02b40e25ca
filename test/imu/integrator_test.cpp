// The noise-free IMU integrator against closed-form motions.
#include <cmath>
#include <functional>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/imu/integrator.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// The true motion at time t (s).
struct Truth {
  Matrix3d R_world_imu;
  Vector3d p_world_imu, v_world_imu;
  Vector3d a_world;    // d v / dt
  Vector3d omega_imu;  // body angular rate: dR/dt = R Hat(omega)
};
using Motion = std::function<Truth(double)>;

const Vector3d kGravity(0.0, 0.0, -9.81);

Matrix3d Rx(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitX()).toRotationMatrix(); }
Matrix3d Ry(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitY()).toRotationMatrix(); }
Matrix3d Rz(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitZ()).toRotationMatrix(); }

// Ideal IMU samples at times offset_ns + k * period_ns covering [t0, t1] with
// one sample of margin on both sides; biases added to the measurements.
std::vector<ImuSample> Simulate(const Motion& motion, TimeNs t0_ns, TimeNs t1_ns, TimeNs period_ns,
                                TimeNs offset_ns, const Vector3d& g_world,
                                const Vector3d& bg = Vector3d::Zero(),
                                const Vector3d& ba = Vector3d::Zero()) {
  std::vector<ImuSample> samples;
  const TimeNs k0 = (t0_ns - offset_ns) / period_ns - 1;
  const TimeNs k1 = (t1_ns - offset_ns) / period_ns + 2;
  for (TimeNs k = k0; k <= k1; ++k) {
    ImuSample s;
    s.t_ns = offset_ns + k * period_ns;
    const Truth x = motion(NsToSeconds(s.t_ns));
    s.acc_imu = x.R_world_imu.transpose() * (x.a_world - g_world) + ba;
    s.gyro_imu = x.omega_imu + bg;
    samples.push_back(s);
  }
  return samples;
}

ImuKinematics TrueKinematics(const Motion& motion, TimeNs t_ns) {
  const Truth x = motion(NsToSeconds(t_ns));
  ImuKinematics k;
  k.t_ns = t_ns;
  k.R_world_imu = x.R_world_imu;
  k.p_world_imu = x.p_world_imu;
  k.v_world_imu = x.v_world_imu;
  return k;
}

struct Errors {
  double rot, pos, vel;
};

Errors Compare(const ImuKinematics& a, const ImuKinematics& b) {
  EXPECT_EQ(a.t_ns, b.t_ns);
  return {so3::Log(a.R_world_imu.transpose() * b.R_world_imu).norm(),
          (a.p_world_imu - b.p_world_imu).norm(), (a.v_world_imu - b.v_world_imu).norm()};
}

// Constant body rate w from R0, constant world acceleration a.
Motion ConstantRateAndAcceleration(const Matrix3d& R0, const Vector3d& w, const Vector3d& p0,
                                   const Vector3d& v0, const Vector3d& a) {
  return [=](double t) {
    return Truth{R0 * so3::Exp(w * t), p0 + v0 * t + 0.5 * a * t * t, v0 + a * t, a, w};
  };
}

// Horizontal circle of radius r at rate W, the body yawing with it (plus a
// fixed tilt), so the gyro reads a constant and the accelerometer rotates.
Motion Circle(double r, double W, const Matrix3d& tilt) {
  return [=](double t) {
    const double c = std::cos(W * t), s = std::sin(W * t);
    return Truth{Rz(W * t) * tilt, Vector3d(r * c, r * s, 1.0), Vector3d(-r * W * s, r * W * c, 0),
                 Vector3d(-r * W * W * c, -r * W * W * s, 0), tilt.transpose() * Vector3d(0, 0, W)};
  };
}

// Smooth 6-dof motion: R = Rz(psi) Ry(theta) Rx(phi) with sinusoidal angles.
Motion Wobble() {
  return [](double t) {
    const double psi = 0.8 * std::sin(0.9 * t), dpsi = 0.72 * std::cos(0.9 * t);
    const double th = 0.3 * std::sin(1.7 * t + 0.2), dth = 0.51 * std::cos(1.7 * t + 0.2);
    const double ph = 0.4 * std::cos(2.3 * t), dph = -0.92 * std::sin(2.3 * t);
    const Matrix3d Rzy = Rz(psi) * Ry(th);
    Truth x;
    x.R_world_imu = Rzy * Rx(ph);
    x.omega_imu =
        Rx(ph).transpose() * (Ry(th).transpose() * Vector3d(0, 0, dpsi) + Vector3d(0, dth, 0)) +
        Vector3d(dph, 0, 0);
    x.p_world_imu = Vector3d(2 * std::sin(0.7 * t), 3 * std::cos(0.5 * t), 0.5 * std::sin(1.1 * t));
    x.v_world_imu =
        Vector3d(1.4 * std::cos(0.7 * t), -1.5 * std::sin(0.5 * t), 0.55 * std::cos(1.1 * t));
    x.a_world =
        Vector3d(-0.98 * std::sin(0.7 * t), -0.75 * std::cos(0.5 * t), -0.605 * std::sin(1.1 * t));
    return x;
  };
}

TEST(ImuIntegrator, WobbleOracleIsSelfConsistent) {
  // Guard the test oracle itself: omega and a must be the derivatives of R, v.
  const Motion m = Wobble();
  const double h = 1e-6;
  for (double t : {0.0, 0.37, 1.9, 4.2}) {
    const Truth x = m(t), xp = m(t + h), xm = m(t - h);
    const Vector3d omega_num =
        so3::Vee(x.R_world_imu.transpose() * (xp.R_world_imu - xm.R_world_imu) / (2 * h));
    EXPECT_LT((omega_num - x.omega_imu).norm(), 1e-8);
    EXPECT_LT(((xp.v_world_imu - xm.v_world_imu) / (2 * h) - x.a_world).norm(), 1e-8);
    EXPECT_LT(((xp.p_world_imu - xm.p_world_imu) / (2 * h) - x.v_world_imu).norm(), 1e-8);
  }
}

TEST(ImuIntegrator, InterpolatesLinearlyAndHoldsOutside) {
  std::vector<ImuSample> s(2);
  s[0].t_ns = 1000;
  s[0].acc_imu = Vector3d(1, 2, 3);
  s[0].gyro_imu = Vector3d(0, 0, 0);
  s[1].t_ns = 2000;
  s[1].acc_imu = Vector3d(3, 2, 1);
  s[1].gyro_imu = Vector3d(1, -1, 2);
  const ImuSample mid = InterpolateImu(s, 1250);
  EXPECT_EQ(mid.t_ns, 1250);
  EXPECT_LT((mid.acc_imu - Vector3d(1.5, 2, 2.5)).norm(), 1e-15);
  EXPECT_LT((mid.gyro_imu - Vector3d(0.25, -0.25, 0.5)).norm(), 1e-15);
  EXPECT_EQ(InterpolateImu(s, 0).acc_imu, s[0].acc_imu);
  EXPECT_EQ(InterpolateImu(s, 5000).gyro_imu, s[1].gyro_imu);
  EXPECT_EQ(InterpolateImu(s, 2000).acc_imu, s[1].acc_imu);
}

TEST(ImuIntegrator, ZeroTimeSpanReturnsStart) {
  ImuKinematics start;
  start.t_ns = 42;
  start.p_world_imu = Vector3d(1, 2, 3);
  const ImuKinematics end = Integrate(start, {}, 42, Vector3d::Zero(), Vector3d::Zero(), kGravity);
  EXPECT_EQ(end.t_ns, 42);
  EXPECT_EQ(end.p_world_imu, start.p_world_imu);
}

TEST(ImuIntegrator, StandingStillWithGravityStaysStill) {
  // Random attitude at rest, biased sensor, start and end between samples.
  std::mt19937 rng(41);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Matrix3d R0 = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    const Vector3d bg = 0.01 * Vector3d(n(rng), n(rng), n(rng));
    const Vector3d ba = 0.1 * Vector3d(n(rng), n(rng), n(rng));
    const Motion m = ConstantRateAndAcceleration(R0, Vector3d::Zero(), Vector3d(1, 2, 3),
                                                 Vector3d::Zero(), Vector3d::Zero());
    const TimeNs t0 = 123457, t1 = 10 * kNsPerSecond + 777;
    const auto samples = Simulate(m, t0, t1, 5000000, 1234567, kGravity, bg, ba);
    const ImuKinematics end = Integrate(TrueKinematics(m, t0), samples, t1, bg, ba, kGravity);
    const Errors e = Compare(end, TrueKinematics(m, t1));
    EXPECT_LT(e.rot, 1e-12);
    EXPECT_LT(e.pos, 1e-9);
    EXPECT_LT(e.vel, 1e-10);
  }
}

TEST(ImuIntegrator, ConstantAccelerationIsExactAtUnalignedTimes) {
  // Fixed attitude, constant world acceleration: the trapezoid rule is exact
  // for any partition, including partial first and last intervals.
  std::mt19937 rng(42);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Matrix3d R0 = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    const Vector3d a(n(rng), n(rng), n(rng)), v0(n(rng), n(rng), n(rng));
    const Motion m = ConstantRateAndAcceleration(R0, Vector3d::Zero(), Vector3d(5, -1, 2), v0, a);
    const TimeNs t0 = 3333333, t1 = 5 * kNsPerSecond + 4444444;
    const auto samples = Simulate(m, t0, t1, 10000000, 7000001, kGravity);
    const ImuKinematics end =
        Integrate(TrueKinematics(m, t0), samples, t1, Vector3d::Zero(), Vector3d::Zero(), kGravity);
    const Errors e = Compare(end, TrueKinematics(m, t1));
    EXPECT_LT(e.rot, 1e-14);
    EXPECT_LT(e.pos, 1e-9);
    EXPECT_LT(e.vel, 1e-10);
  }
}

TEST(ImuIntegrator, ConstantRotationRateIsExact) {
  // Constant body rate: rotation exact at any partition. Without gravity and
  // with zero acceleration the position is linear in time.
  std::mt19937 rng(43);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Matrix3d R0 = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    const Vector3d w(n(rng), n(rng), n(rng)), v0(n(rng), n(rng), n(rng));
    const Motion m = ConstantRateAndAcceleration(R0, w, Vector3d::Zero(), v0, Vector3d::Zero());
    const TimeNs t0 = 1000001, t1 = 3 * kNsPerSecond + 2345;
    const auto samples = Simulate(m, t0, t1, 2500000, 333, Vector3d::Zero());
    const ImuKinematics end = Integrate(TrueKinematics(m, t0), samples, t1, Vector3d::Zero(),
                                        Vector3d::Zero(), Vector3d::Zero());
    const Errors e = Compare(end, TrueKinematics(m, t1));
    EXPECT_LT(e.rot, 1e-11);
    EXPECT_LT(e.pos, 1e-11);
    EXPECT_LT(e.vel, 1e-12);
  }
}

TEST(ImuIntegrator, ConstantRateWithGravityCompensationIsExactAtSampleTimes) {
  // Spinning at a constant rate while moving at constant world acceleration
  // under gravity: at sample-aligned times the rotation is exact at every
  // knot, so the world acceleration at the knots is exact and the trapezoid
  // rule integrates the (constant) world acceleration exactly.
  std::mt19937 rng(44);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Matrix3d R0 = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    const Vector3d w(n(rng), n(rng), n(rng)), v0(n(rng), n(rng), n(rng));
    const Vector3d a(n(rng), n(rng), n(rng));
    const Vector3d bg = 0.01 * Vector3d(n(rng), n(rng), n(rng));
    const Vector3d ba = 0.1 * Vector3d(n(rng), n(rng), n(rng));
    const Motion m = ConstantRateAndAcceleration(R0, w, Vector3d(0, 1, 0), v0, a);
    const TimeNs t0 = 0, t1 = 4 * kNsPerSecond;
    const auto samples = Simulate(m, t0, t1, 5000000, 0, kGravity, bg, ba);
    const ImuKinematics end = Integrate(TrueKinematics(m, t0), samples, t1, bg, ba, kGravity);
    const Errors e = Compare(end, TrueKinematics(m, t1));
    EXPECT_LT(e.rot, 1e-11);
    EXPECT_LT(e.pos, 1e-8);
    EXPECT_LT(e.vel, 1e-9);
  }
}

TEST(ImuIntegrator, CircularMotionAt1kHz) {
  const Matrix3d tilt = Rx(0.2) * Ry(-0.1);
  const Motion m = Circle(5.0, 1.0, tilt);
  const TimeNs t0 = 0, t1 = 10 * kNsPerSecond + 500000;  // ends between samples
  const auto samples = Simulate(m, t0, t1, 1000000, 0, kGravity);
  const ImuKinematics end =
      Integrate(TrueKinematics(m, t0), samples, t1, Vector3d::Zero(), Vector3d::Zero(), kGravity);
  const Errors e = Compare(end, TrueKinematics(m, t1));
  EXPECT_LT(e.rot, 1e-11);
  // Measured 4.9e-6 m and 8.0e-7 m/s (second-order scheme, 10 s at 1 kHz).
  EXPECT_LT(e.pos, 2e-5);
  EXPECT_LT(e.vel, 3e-6);
}

TEST(ImuIntegrator, ErrorShrinksQuadraticallyWithRate) {
  const Motion m = Wobble();
  const TimeNs t0 = 0, t1 = 5 * kNsPerSecond;
  const Vector3d bg(0.01, -0.02, 0.005), ba(0.1, 0.05, -0.2);
  std::vector<Errors> errors;
  for (double rate_hz : {100.0, 200.0, 400.0, 800.0}) {
    const TimeNs period = SecondsToNs(1.0 / rate_hz);
    const auto samples = Simulate(m, t0, t1, period, 0, kGravity, bg, ba);
    const ImuKinematics end = Integrate(TrueKinematics(m, t0), samples, t1, bg, ba, kGravity);
    errors.push_back(Compare(end, TrueKinematics(m, t1)));
  }
  for (size_t i = 1; i < errors.size(); ++i) {
    // Second order: doubling the rate divides the error by ~4.
    EXPECT_LT(errors[i].rot, 0.3 * errors[i - 1].rot) << i;
    EXPECT_LT(errors[i].pos, 0.3 * errors[i - 1].pos) << i;
    EXPECT_LT(errors[i].vel, 0.3 * errors[i - 1].vel) << i;
  }
  // Measured at 800 Hz: 1.2e-7 rad, 8.8e-6 m, 6.1e-6 m/s after 5 s.
  EXPECT_LT(errors.back().rot, 5e-7);
  EXPECT_LT(errors.back().pos, 4e-5);
  EXPECT_LT(errors.back().vel, 3e-5);
}

TEST(ImuIntegrator, BackwardIntegrationUndoesForwardIntegration) {
  const Motion m = Wobble();
  const TimeNs t0 = 2500000, t1 = 2 * kNsPerSecond + 1234567;
  const Vector3d bg(0.01, -0.02, 0.005), ba(0.1, 0.05, -0.2);
  const auto samples = Simulate(m, t0, t1, 5000000, 0, kGravity, bg, ba);
  const ImuKinematics start = TrueKinematics(m, t0);
  const ImuKinematics end = Integrate(start, samples, t1, bg, ba, kGravity);
  const ImuKinematics back = Integrate(end, samples, t0, bg, ba, kGravity);
  const Errors e = Compare(back, start);
  EXPECT_LT(e.rot, 1e-13);
  EXPECT_LT(e.pos, 1e-11);
  EXPECT_LT(e.vel, 1e-12);
  // Backward from the true end state lands near the true start (the same
  // second-order accuracy as forward).
  const Errors eb = Compare(Integrate(TrueKinematics(m, t1), samples, t0, bg, ba, kGravity), start);
  EXPECT_LT(eb.rot, 5e-5);  // measured 8.9e-6 rad, 6.2e-5 m, 5.0e-5 m/s at 200 Hz
  EXPECT_LT(eb.pos, 3e-4);
  EXPECT_LT(eb.vel, 3e-4);
}

TEST(ImuIntegrator, TrajectoryHasAStateAtEveryKnot) {
  const Motion m = Wobble();
  const TimeNs period = 2500000;  // 400 Hz
  const TimeNs t0 = 1000000, t1 = 500000000 + 700000;
  const auto samples = Simulate(m, t0, t1, period, 0, kGravity);
  const ImuKinematics start = TrueKinematics(m, t0);
  const auto states =
      IntegrateTrajectory(start, samples, t1, Vector3d::Zero(), Vector3d::Zero(), kGravity);
  // Knots: t0, the samples strictly inside (2.5 ms ... 500 ms), t1.
  ASSERT_EQ(states.size(), 2u + 200u);
  EXPECT_EQ(states.front().t_ns, t0);
  EXPECT_EQ(states[1].t_ns, period);
  EXPECT_EQ(states.back().t_ns, t1);
  for (size_t i = 1; i < states.size(); ++i) {
    EXPECT_GT(states[i].t_ns, states[i - 1].t_ns);
    const Errors e = Compare(states[i], TrueKinematics(m, states[i].t_ns));
    EXPECT_LT(e.pos, 1e-4) << i;
  }
  const Errors same = Compare(
      states.back(), Integrate(start, samples, t1, Vector3d::Zero(), Vector3d::Zero(), kGravity));
  EXPECT_EQ(same.pos, 0.0);
  // Backwards, the knots run in decreasing time.
  const auto back =
      IntegrateTrajectory(states.back(), samples, t0, Vector3d::Zero(), Vector3d::Zero(), kGravity);
  ASSERT_EQ(back.size(), states.size());
  for (size_t i = 0; i < back.size(); ++i)
    EXPECT_EQ(back[i].t_ns, states[states.size() - 1 - i].t_ns);
}

}  // namespace
}  // namespace rvlio

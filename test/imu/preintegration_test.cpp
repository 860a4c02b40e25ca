// On-manifold IMU preintegration: against closed-form motion, against the
// integrator, bias Jacobians against numeric re-integration, covariance
// against a Monte-Carlo estimate.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/imu/integrator.h"
#include "rvlio/imu/preintegration.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Vector9d = Eigen::Matrix<double, 9, 1>;

const Vector3d kGravityPreint(0.0, 0.0, -9.81);

Matrix3d RotX(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitX()).toRotationMatrix(); }
Matrix3d RotY(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitY()).toRotationMatrix(); }
Matrix3d RotZ(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitZ()).toRotationMatrix(); }

// Smooth 6-dof closed-form motion: R = RotZ(psi) RotY(theta) RotX(phi), sinusoids.
struct PreintTruth {
  Matrix3d R;
  Vector3d p, v, a_world, omega_imu;
};

PreintTruth Swing(double t) {
  const double psi = 0.9 * std::sin(0.8 * t), dpsi = 0.72 * std::cos(0.8 * t);
  const double th = 0.35 * std::sin(1.5 * t + 0.3), dth = 0.525 * std::cos(1.5 * t + 0.3);
  const double ph = 0.3 * std::cos(2.1 * t), dph = -0.63 * std::sin(2.1 * t);
  PreintTruth x;
  x.R = RotZ(psi) * RotY(th) * RotX(ph);
  x.omega_imu =
      RotX(ph).transpose() * (RotY(th).transpose() * Vector3d(0, 0, dpsi) + Vector3d(0, dth, 0)) +
      Vector3d(dph, 0, 0);
  x.p = Vector3d(3 * std::sin(0.6 * t), 2 * std::cos(0.4 * t), 0.4 * std::sin(1.3 * t));
  x.v = Vector3d(1.8 * std::cos(0.6 * t), -0.8 * std::sin(0.4 * t), 0.52 * std::cos(1.3 * t));
  x.a_world =
      Vector3d(-1.08 * std::sin(0.6 * t), -0.32 * std::cos(0.4 * t), -0.676 * std::sin(1.3 * t));
  return x;
}

ImuKinematics TrueState(TimeNs t_ns) {
  const PreintTruth x = Swing(NsToSeconds(t_ns));
  ImuKinematics k;
  k.t_ns = t_ns;
  k.R_world_imu = x.R;
  k.p_world_imu = x.p;
  k.v_world_imu = x.v;
  return k;
}

// Ideal samples every period_ns (offset offset_ns) covering [t0, t1] with a
// margin, biases added.
std::vector<ImuSample> Simulate(TimeNs t0, TimeNs t1, TimeNs period_ns, TimeNs offset_ns,
                                const Vector3d& bg = Vector3d::Zero(),
                                const Vector3d& ba = Vector3d::Zero()) {
  std::vector<ImuSample> samples;
  for (TimeNs k = (t0 - offset_ns) / period_ns - 1; k <= (t1 - offset_ns) / period_ns + 2; ++k) {
    ImuSample s;
    s.t_ns = offset_ns + k * period_ns;
    const PreintTruth x = Swing(NsToSeconds(s.t_ns));
    s.acc_imu = x.R.transpose() * (x.a_world - kGravityPreint) + ba;
    s.gyro_imu = x.omega_imu + bg;
    samples.push_back(s);
  }
  return samples;
}

ImuNoise PreintNoise() {
  ImuNoise n;
  n.gyro_noise_density = 2e-3;
  n.accel_noise_density = 2e-2;
  n.gyro_bias_random_walk = 1e-4;
  n.accel_bias_random_walk = 1e-3;
  return n;
}

// [Log(a.dR^T b.dR), b.dv - a.dv, b.dp - a.dp]: b relative to a in the error
// state of the preintegration.
Vector9d DeltaError(const PreintegratedDelta& a, const PreintegratedDelta& b) {
  Vector9d e;
  e << so3::Log(a.dR.transpose() * b.dR), b.dv - a.dv, b.dp - a.dp;
  return e;
}

double RotError(const ImuKinematics& a, const ImuKinematics& b) {
  return so3::Log(a.R_world_imu.transpose() * b.R_world_imu).norm();
}

TEST(ImuPreintegration, EmptyIntervalIsIdentity) {
  const auto samples = Simulate(0, kNsPerSecond, 5000000, 0);
  const auto pre = ImuPreintegration::FromSamples(samples, 123456789, 123456789, PreintNoise(),
                                                  Vector3d::Zero(), Vector3d::Zero());
  EXPECT_EQ(pre.dt(), 0.0);
  EXPECT_EQ(pre.knots().size(), 1u);
  EXPECT_TRUE(pre.dR().isApprox(Matrix3d::Identity()));
  EXPECT_EQ(pre.dv().norm(), 0.0);
  EXPECT_EQ(pre.covariance().norm(), 0.0);
}

TEST(ImuPreintegration, PredictionEqualsIntegratorAtUnalignedTimes) {
  // Same discrete scheme as imu/integrator.h: prediction == Integrate() up to
  // rounding, from any start state, with biases.
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    const Vector3d bg = 0.01 * Vector3d(n(rng), n(rng), n(rng));
    const Vector3d ba = 0.1 * Vector3d(n(rng), n(rng), n(rng));
    const TimeNs t0 = 1000000 * (trial + 1) + 1234, t1 = t0 + 300000000 + 98765;
    const auto samples = Simulate(t0, t1, 5000000, 777, bg, ba);
    const auto pre = ImuPreintegration::FromSamples(samples, t0, t1, PreintNoise(), bg, ba);
    EXPECT_EQ(pre.start_ns(), t0);
    EXPECT_EQ(pre.end_ns(), t1);
    EXPECT_NEAR(pre.dt(), NsToSeconds(t1 - t0), 1e-12);
    ImuKinematics x0;
    x0.t_ns = t0;
    x0.R_world_imu = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    x0.p_world_imu = Vector3d(n(rng), n(rng), n(rng));
    x0.v_world_imu = Vector3d(n(rng), n(rng), n(rng));
    const ImuKinematics a = pre.Predict(x0, bg, ba, kGravityPreint);
    const ImuKinematics b = Integrate(x0, samples, t1, bg, ba, kGravityPreint);
    EXPECT_EQ(a.t_ns, t1);
    EXPECT_LT(RotError(a, b), 1e-13);
    EXPECT_LT((a.p_world_imu - b.p_world_imu).norm(), 1e-12);
    EXPECT_LT((a.v_world_imu - b.v_world_imu).norm(), 1e-12);
  }
}

TEST(ImuPreintegration, PredictsTheTrueStateAtHighRate) {
  // Noise-free, biased 1 kHz samples of a closed-form motion; the prediction
  // from the true state at t_i lands on the true state at t_j (second order).
  const Vector3d bg(0.004, -0.003, 0.002), ba(0.05, -0.08, 0.03);
  for (TimeNs t0 : {TimeNs(0), TimeNs(1234567891), TimeNs(3 * kNsPerSecond + 55555)}) {
    const TimeNs t1 = t0 + 500000000 + 333;
    const auto samples = Simulate(t0, t1, 1000000, 250000, bg, ba);
    const auto pre = ImuPreintegration::FromSamples(samples, t0, t1, PreintNoise(), bg, ba);
    const ImuKinematics x = pre.Predict(TrueState(t0), bg, ba, kGravityPreint);
    const ImuKinematics truth = TrueState(t1);
    EXPECT_LT(RotError(x, truth), 1e-7);
    EXPECT_LT((x.p_world_imu - truth.p_world_imu).norm(), 1e-6);
    EXPECT_LT((x.v_world_imu - truth.v_world_imu).norm(), 2e-6);
  }
}

TEST(ImuPreintegration, AppendEqualsFromSamples) {
  const TimeNs t0 = 10000000, t1 = 210000000;
  const auto samples = Simulate(t0, t1, 5000000, 0);
  const Vector3d bg(0.01, 0.0, -0.01), ba(0.1, 0.2, 0.0);
  const auto ref = ImuPreintegration::FromSamples(samples, t0, t1, PreintNoise(), bg, ba);
  ImuPreintegration inc(PreintNoise(), bg, ba);
  for (const ImuSample& s : samples)
    if (s.t_ns >= t0 && s.t_ns <= t1) {
      inc.Append(s);
      inc.Append(s);  // a repeated time adds nothing
    }
  EXPECT_EQ(inc.knots().size(), ref.knots().size());
  EXPECT_LT(DeltaError(ref.delta(), inc.delta()).norm(), 1e-15);
  EXPECT_LT((ref.covariance() - inc.covariance()).norm(), 1e-18);
  EXPECT_LT((ref.bias_jacobian() - inc.bias_jacobian()).norm(), 1e-15);
}

// Central differences of the re-integrated deltas w.r.t. each bias component.
TEST(ImuPreintegration, BiasJacobiansMatchNumericReintegration) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    const TimeNs t0 = 200000000 * trial + 4321, t1 = t0 + 150000000 + 1111;
    const auto samples = Simulate(t0, t1, 5000000, 1000);
    const Vector3d bg = 0.02 * Vector3d(n(rng), n(rng), n(rng));
    const Vector3d ba = 0.2 * Vector3d(n(rng), n(rng), n(rng));
    const auto pre = ImuPreintegration::FromSamples(samples, t0, t1, PreintNoise(), bg, ba);
    Eigen::Matrix<double, 9, 6> J_num;
    const double eps = 1e-6;
    for (int k = 0; k < 6; ++k) {
      Vector3d dbg = Vector3d::Zero(), dba = Vector3d::Zero();
      (k < 3 ? dbg : dba)(k % 3) = eps;
      const auto plus =
          ImuPreintegration::FromSamples(samples, t0, t1, PreintNoise(), bg + dbg, ba + dba);
      const auto minus =
          ImuPreintegration::FromSamples(samples, t0, t1, PreintNoise(), bg - dbg, ba - dba);
      J_num.col(k) = (DeltaError(pre.delta(), plus.delta()) -
                      DeltaError(pre.delta(), minus.delta())) / (2 * eps);
    }
    EXPECT_LT((J_num - pre.bias_jacobian()).cwiseAbs().maxCoeff(), 1e-8)
        << "numeric\n" << J_num << "\nanalytic\n" << pre.bias_jacobian();
    EXPECT_LT((pre.bias_jacobian().block<3, 3>(0, 3).norm()), 1e-15);  // dR does not see b_a
    EXPECT_GT(pre.J_p_ba().norm(), 1e-3);  // and the test is not vacuous
    EXPECT_GT(pre.J_R_bg().norm(), 1e-2);
  }
}

TEST(ImuPreintegration, FirstOrderCorrectionIsCloseToReintegration) {
  std::mt19937 rng(12);
  std::normal_distribution<double> n(0.0, 1.0);
  const TimeNs t0 = 55555, t1 = 100000000 + 77777;  // 0.1 s: one scan at 10 Hz
  const auto samples = Simulate(t0, t1, 5000000, 0);
  const auto pre = ImuPreintegration::FromSamples(samples, t0, t1, PreintNoise(), Vector3d::Zero(),
                                                  Vector3d::Zero());
  for (int trial = 0; trial < 20; ++trial) {
    const Vector3d bg = 0.003 * Vector3d(n(rng), n(rng), n(rng));  // rad/s
    const Vector3d ba = 0.05 * Vector3d(n(rng), n(rng), n(rng));   // m/s^2
    const auto full = ImuPreintegration::FromSamples(samples, t0, t1, PreintNoise(), bg, ba);
    const Vector9d uncorrected = DeltaError(full.delta(), pre.delta());
    const Vector9d corrected = DeltaError(full.delta(), pre.Corrected(bg, ba));
    // The remainder is second order: orders of magnitude below the first-order
    // change (measured ratios 1e-5 .. 4e-4, remainders <= 4.4e-6) ...
    EXPECT_LT(corrected.norm(), 1e-3 * uncorrected.norm()) << trial;
    EXPECT_LT(corrected.norm(), 1e-5) << trial;
    // ... and halving the bias change quarters it.
    const auto half = ImuPreintegration::FromSamples(samples, t0, t1, PreintNoise(), bg / 2, ba / 2);
    const double corrected_half = DeltaError(half.delta(), pre.Corrected(bg / 2, ba / 2)).norm();
    EXPECT_NEAR(corrected_half / corrected.norm(), 0.25, 0.03) << trial;
  }
}

TEST(ImuPreintegration, RepropagatesOnlyWhenTheBiasMovedFar) {
  const TimeNs t0 = 0, t1 = 200000000;
  const auto samples = Simulate(t0, t1, 5000000, 0);
  auto pre = ImuPreintegration::FromSamples(samples, t0, t1, PreintNoise(), Vector3d::Zero(),
                                            Vector3d::Zero());
  const PreintegratedDelta before = pre.delta();
  EXPECT_FALSE(pre.RepropagateIfBiasMoved(Vector3d(0.001, 0, 0), Vector3d(0, 0.01, 0), 0.01, 0.1));
  EXPECT_EQ(DeltaError(before, pre.delta()).norm(), 0.0);
  EXPECT_EQ(pre.bg_lin().norm(), 0.0);
  const Vector3d bg(0.0, 0.05, 0.0), ba(0.0, 0.01, 0.0);
  EXPECT_TRUE(pre.RepropagateIfBiasMoved(bg, ba, 0.01, 0.1));
  const auto ref = ImuPreintegration::FromSamples(samples, t0, t1, PreintNoise(), bg, ba);
  EXPECT_EQ(pre.bg_lin(), bg);
  EXPECT_EQ(pre.ba_lin(), ba);
  EXPECT_LT(DeltaError(ref.delta(), pre.delta()).norm(), 1e-15);
  EXPECT_LT((ref.bias_jacobian() - pre.bias_jacobian()).norm(), 1e-15);
  EXPECT_LT((ref.covariance() - pre.covariance()).norm(), 1e-18);
  EXPECT_EQ(pre.dt(), ref.dt());
}

TEST(ImuPreintegration, CovarianceDoesNotDependOnTheRate) {
  // The same motion sampled at 200 Hz and 1 kHz: the covariance describes the
  // continuous-time noise densities, not the sample rate.
  const TimeNs t0 = 3000000, t1 = 403000000;
  const Vector3d z = Vector3d::Zero();
  const auto slow = ImuPreintegration::FromSamples(Simulate(t0, t1, 5000000, 0), t0, t1,
                                                   PreintNoise(), z, z);
  const auto fast = ImuPreintegration::FromSamples(Simulate(t0, t1, 1000000, 0), t0, t1,
                                                   PreintNoise(), z, z);
  for (int i = 0; i < 9; ++i)
    EXPECT_NEAR(fast.covariance()(i, i) / slow.covariance()(i, i), 1.0, 0.01) << i;
  // Closed form for the rotation block: sigma_g^2 dt I (rotation is not
  // affected by the accelerometer).
  const double sg = PreintNoise().gyro_noise_density;
  EXPECT_NEAR(fast.covariance()(0, 0), sg * sg * 0.4, 1e-3 * sg * sg * 0.4);
}

TEST(ImuPreintegration, CovarianceMatchesMonteCarlo) {
  // 2000 re-integrations of samples with independent white noise per sample
  // (std sigma / sqrt(period), ImuNoise's convention, as the simulator does).
  const ImuNoise noise = PreintNoise();
  const TimeNs period = 5000000, t0 = 1234567, t1 = 501234567 + 2500000;
  const std::vector<ImuSample> clean = Simulate(t0, t1, period, 0);
  const Vector3d z = Vector3d::Zero();
  const auto nominal = ImuPreintegration::FromSamples(clean, t0, t1, noise, z, z);
  std::mt19937 rng(2024);
  std::normal_distribution<double> n(0.0, 1.0);
  const double sg = noise.gyro_noise_density / std::sqrt(NsToSeconds(period));
  const double sa = noise.accel_noise_density / std::sqrt(NsToSeconds(period));
  const int kTrials = 2000;
  Matrix9d C = Matrix9d::Zero();
  Vector9d mean = Vector9d::Zero();
  for (int trial = 0; trial < kTrials; ++trial) {
    std::vector<ImuSample> noisy = clean;
    for (ImuSample& s : noisy) {
      s.gyro_imu += sg * Vector3d(n(rng), n(rng), n(rng));
      s.acc_imu += sa * Vector3d(n(rng), n(rng), n(rng));
    }
    const auto pre = ImuPreintegration::FromSamples(noisy, t0, t1, noise, z, z);
    const Vector9d e = DeltaError(nominal.delta(), pre.delta());
    mean += e;
    C += e * e.transpose();
  }
  mean /= kTrials;
  C = C / kTrials - mean * mean.transpose();
  const Matrix9d& P = nominal.covariance();
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(C(i, i) / P(i, i), 1.0, 0.15) << i;
  // Whitened: L^-1 C L^-T ~ I, which also checks the correlations.
  const Eigen::LLT<Matrix9d> llt(P);
  ASSERT_EQ(llt.info(), Eigen::Success);
  const Matrix9d L_inv = llt.matrixL().solve(Matrix9d::Identity());
  const Matrix9d W = L_inv * C * L_inv.transpose();
  EXPECT_LT((W - Matrix9d::Identity()).cwiseAbs().maxCoeff(), 0.15) << W;
}

}  // namespace
}  // namespace rvlio

// Oracle: the noise-free simulated IMU, integrated from the true initial
// state, reproduces the true trajectory (docs/design.md section 9). The integrator
// is written here (midpoint rotation, trapezoidal acceleration) so the test
// depends on nothing but the simulator.
#include <cmath>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "rvlio/sim/imu_sim.h"
#include "rvlio/sim/presets.h"
#include "rvlio/sim/simulator.h"

namespace rvlio::sim {
namespace {

Eigen::Matrix3d Exp(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  if (angle < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix();
}

double RotationAngle(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle(); }

SimOptions NoiseFree(SimOptions o, double imu_rate) {
  o.imu.rate = imu_rate;
  o.imu.gyro_noise_density = o.imu.accel_noise_density = 0.0;
  o.imu.gyro_bias_random_walk = o.imu.accel_bias_random_walk = 0.0;
  o.imu.gyro_bias = {0.0, 0.0, 0.0};
  o.imu.accel_bias = {0.0, 0.0, 0.0};
  return o;
}

struct OracleResult {
  double max_position_error = 0.0;  // m
  double max_rotation_error = 0.0;  // rad
  double max_velocity_error = 0.0;  // m/s
};

// Integrates the IMU of `o` over its whole duration without casting rays.
OracleResult IntegrateAndCompare(const SimOptions& o) {
  auto sim = Simulator::Create(o);
  EXPECT_TRUE(sim.ok()) << sim.status().message();
  const FlightTrajectory& traj = (*sim)->trajectory();
  ImuSimulator imu(traj, o.imu, static_cast<uint64_t>(o.seed));
  const Eigen::Vector3d g(0.0, 0.0, -o.imu.gravity);
  ImuSample prev = imu.Next();
  TruthState x0 = traj.At(prev.t_ns);
  Eigen::Matrix3d R = x0.T_world_imu.R;
  Eigen::Vector3d p = x0.T_world_imu.t, v = x0.v_world_imu;
  OracleResult r;
  for (int64_t k = 1; k < (*sim)->imu_count(); ++k) {
    const ImuSample cur = imu.Next();
    const double h = NsToSeconds(cur.t_ns - prev.t_ns);
    const Eigen::Matrix3d R1 = R * Exp(0.5 * (prev.gyro_imu + cur.gyro_imu) * h);
    const Eigen::Vector3d a = 0.5 * (R * prev.acc_imu + R1 * cur.acc_imu) + g;
    p += v * h + 0.5 * a * h * h;
    v += a * h;
    R = R1;
    prev = cur;
    const TruthState t = traj.At(cur.t_ns);
    r.max_position_error = std::max(r.max_position_error, (p - t.T_world_imu.t).norm());
    r.max_velocity_error = std::max(r.max_velocity_error, (v - t.v_world_imu).norm());
    r.max_rotation_error =
        std::max(r.max_rotation_error, RotationAngle(t.T_world_imu.R.transpose() * R));
  }
  return r;
}

TEST(ImuOracle, NoiseFreeImuReproducesTunnelFlightOver60s) {
  SimOptions o = NoiseFree(*PresetOptions("tunnel"), 1000.0);
  o.duration = 60.0;
  const OracleResult r = IntegrateAndCompare(o);
  EXPECT_LT(r.max_position_error, 0.01);
  EXPECT_LT(r.max_rotation_error, 1e-4);
  RecordProperty("max_position_error_m", std::to_string(r.max_position_error));
  std::printf(
      "tunnel 60 s @1 kHz: max position error %.3g m, rotation %.3g rad, velocity %.3g m/s\n",
      r.max_position_error, r.max_rotation_error, r.max_velocity_error);
}

TEST(ImuOracle, NoiseFreeImuReproducesHallFlightWithTurns) {
  SimOptions o = NoiseFree(*PresetOptions("hall"), 1000.0);
  o.duration = 60.0;
  o.trajectory.yaw_amplitude = 0.3;  // larger yaw motion: non-commuting rotations
  const OracleResult r = IntegrateAndCompare(o);
  EXPECT_LT(r.max_position_error, 0.01);
  std::printf("hall 60 s @1 kHz: max position error %.3g m, rotation %.3g rad\n",
              r.max_position_error, r.max_rotation_error);
}

// At the default 200 Hz the same integration still stays within a few cm:
// the signal is smooth enough for the estimators' propagation.
TEST(ImuOracle, DefaultRateIsIntegrableToCentimetres) {
  SimOptions o = NoiseFree(*PresetOptions("tunnel"), 200.0);
  const OracleResult r = IntegrateAndCompare(o);
  EXPECT_LT(r.max_position_error, 0.05);
  std::printf("tunnel %.0f s @200 Hz: max position error %.3g m\n", o.duration,
              r.max_position_error);
}

// The midpoint scheme is (at least) second order: halving the step divides
// the error by four or more. A signal inconsistent with the trajectory (a
// wrong sign, frame or derivative) would not converge.
TEST(ImuOracle, IntegrationErrorConvergesAtSecondOrder) {
  SimOptions o = NoiseFree(*PresetOptions("tunnel"), 250.0);
  o.duration = 30.0;
  const double e1 = IntegrateAndCompare(o).max_position_error;
  o.imu.rate = 500.0;
  const double e2 = IntegrateAndCompare(o).max_position_error;
  EXPECT_GT(e1 / e2, 3.5) << e1 << " " << e2;
}

TEST(ImuNoise, WhiteNoiseAndBiasesMatchTheConfiguredModel) {
  SimOptions o = *PresetOptions("tunnel");
  o.imu.gyro_bias_random_walk = o.imu.accel_bias_random_walk = 0.0;
  o.imu.rate = 400.0;
  o.trajectory.static_duration = 30.0;
  auto sim = Simulator::Create(o);
  ASSERT_TRUE(sim.ok());
  ImuSimulator imu((*sim)->trajectory(), o.imu, 5);
  // Static phase: truth is gyro 0, acc (0, 0, g); samples = bias + white noise.
  const int n = 10000;
  Eigen::Vector3d sg = Eigen::Vector3d::Zero(), sa = Eigen::Vector3d::Zero();
  Eigen::Vector3d qg = Eigen::Vector3d::Zero(), qa = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const ImuSample m = imu.Next();
    const Eigen::Vector3d a = m.acc_imu - Eigen::Vector3d(0, 0, o.imu.gravity);
    sg += m.gyro_imu;
    sa += a;
    qg += m.gyro_imu.cwiseProduct(m.gyro_imu);
    qa += a.cwiseProduct(a);
  }
  const double sigma_g = o.imu.gyro_noise_density * std::sqrt(o.imu.rate);
  const double sigma_a = o.imu.accel_noise_density * std::sqrt(o.imu.rate);
  for (int i = 0; i < 3; ++i) {
    const double mg = sg[i] / n, ma = sa[i] / n;
    EXPECT_NEAR(mg, o.imu.gyro_bias[i], 5.0 * sigma_g / std::sqrt(n));
    EXPECT_NEAR(ma, o.imu.accel_bias[i], 5.0 * sigma_a / std::sqrt(n));
    EXPECT_NEAR(std::sqrt(qg[i] / n - mg * mg), sigma_g, 0.05 * sigma_g);
    EXPECT_NEAR(std::sqrt(qa[i] / n - ma * ma), sigma_a, 0.05 * sigma_a);
  }
}

TEST(ImuNoise, BiasRandomWalkGrowsWithSqrtTime) {
  SimOptions o = *PresetOptions("tunnel");
  o.imu.gyro_noise_density = o.imu.accel_noise_density = 0.0;
  auto sim = Simulator::Create(o);
  ASSERT_TRUE(sim.ok());
  // Over many independent walks, the variance of b(T) - b(0) is sigma_rw^2 T.
  const int walks = 400, steps = 2000;  // 10 s at 200 Hz
  double var_g = 0.0, var_a = 0.0;
  for (int w = 0; w < walks; ++w) {
    ImuSimulator imu((*sim)->trajectory(), o.imu, 1000 + w);
    imu.Next();
    const Eigen::Vector3d bg0 = imu.gyro_bias(), ba0 = imu.accel_bias();
    for (int k = 0; k < steps; ++k) imu.Next();
    var_g += (imu.gyro_bias() - bg0).squaredNorm() / 3.0;
    var_a += (imu.accel_bias() - ba0).squaredNorm() / 3.0;
  }
  const double T = steps / o.imu.rate;
  const double expect_g = o.imu.gyro_bias_random_walk * o.imu.gyro_bias_random_walk * T;
  const double expect_a = o.imu.accel_bias_random_walk * o.imu.accel_bias_random_walk * T;
  // 1200 squared Gaussians: relative std of the mean ~ sqrt(2/1200) = 4 %.
  EXPECT_NEAR(var_g / walks, expect_g, 0.15 * expect_g);
  EXPECT_NEAR(var_a / walks, expect_a, 0.15 * expect_a);
}

TEST(ImuNoise, VibrationAddsASinusoidAtTheMotorFrequency) {
  SimOptions quiet = *PresetOptions("tunnel");
  quiet.imu.gyro_noise_density = quiet.imu.accel_noise_density = 0.0;
  quiet.imu.gyro_bias_random_walk = quiet.imu.accel_bias_random_walk = 0.0;
  quiet.imu.rate = 1000.0;
  SimOptions shaky = quiet;
  shaky.imu.vibration_accel = 2.0;
  shaky.imu.vibration_frequency = 87.0;
  auto s1 = Simulator::Create(quiet), s2 = Simulator::Create(shaky);
  ASSERT_TRUE(s1.ok() && s2.ok());
  ImuSimulator a((*s1)->trajectory(), quiet.imu, 1), b((*s2)->trajectory(), shaky.imu, 1);
  // Project the difference on sin/cos at 87 Hz over 1 s: amplitude 2.0 on z.
  double c = 0.0, s = 0.0;
  for (int k = 0; k < 1000; ++k) {
    const ImuSample ma = a.Next(), mb = b.Next();
    const double d = mb.acc_imu.z() - ma.acc_imu.z();
    const double arg = 2.0 * M_PI * 87.0 * k / 1000.0;
    c += d * std::cos(arg) * 2.0 / 1000;
    s += d * std::sin(arg) * 2.0 / 1000;
  }
  EXPECT_NEAR(std::hypot(c, s), 2.0, 0.02);
}

}  // namespace
}  // namespace rvlio::sim

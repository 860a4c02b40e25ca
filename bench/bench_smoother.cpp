// Micro-benchmarks of the smoother's building blocks:
// - preintegration cost per IMU sample (one Append: deltas, 9x9 covariance,
//   bias Jacobians),
// - one plane factor holding 2000 constraints: residuals only and residuals
//   with the analytic 2000x7 Jacobian,
// - one IMU factor evaluation with all four Jacobians,
// - marginalizing the oldest state of a 10-state window.
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>
#include <ceres/problem.h>

#include "bench_util.h"

#include "rvlio/imu/preintegration.h"
#include "rvlio/factors/imu_factor.h"
#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/marginalization.h"
#include "rvlio/factors/plane_factor.h"

namespace {

using rvlio::ImuNoise;
using rvlio::ImuPreintegration;
using rvlio::ImuSample;
using rvlio::TimeNs;

ImuNoise Noise() { return rvlio::bench::MakeImuNoise(1e-3, 1e-2, 1e-4, 1e-3); }

// A wobbling IMU at rate_hz over [0, duration].
std::vector<ImuSample> Samples(double rate_hz, double duration_s) {
  std::vector<ImuSample> s;
  const TimeNs period = static_cast<TimeNs>(1e9 / rate_hz);
  for (TimeNs t = 0; t <= static_cast<TimeNs>(duration_s * 1e9); t += period) {
    const double ts = rvlio::NsToSeconds(t);
    ImuSample m;
    m.t_ns = t;
    m.gyro_imu = Eigen::Vector3d(0.3 * std::sin(2 * ts), 0.2 * std::cos(3 * ts), 0.5);
    m.acc_imu = Eigen::Vector3d(0.5 * std::cos(ts), 0.1, 9.81);
    s.push_back(m);
  }
  return s;
}

void BM_PreintegrationPerSample(benchmark::State& state) {
  const auto samples = Samples(400.0, 1.0);
  for (auto _ : state) {
    ImuPreintegration pre(Noise(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    for (const ImuSample& s : samples) pre.Append(s);
    benchmark::DoNotOptimize(pre.covariance());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(samples.size()));
}
BENCHMARK(BM_PreintegrationPerSample);

rvlio::ConstraintList RandomConstraints(int n) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  rvlio::ConstraintList list(n);
  for (rvlio::Constraint& c : list) {
    c.p_lidar = 10.0 * Eigen::Vector3d(g(rng), g(rng), g(rng));
    c.normal_world = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    c.q_world = 10.0 * Eigen::Vector3d(g(rng), g(rng), g(rng));
    c.weight = 0.5 + 0.5 * std::abs(g(rng));
  }
  return list;
}

void BM_PlaneFactorEvaluate(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const bool with_jacobian = state.range(1) != 0;
  const rvlio::PlaneFactor f(RandomConstraints(n), rvlio::Pose3(), 0.05);
  double pose[7] = {0.1, -0.2, 0.3, 0.9, 1.0, 2.0, 3.0};
  Eigen::Map<Eigen::Quaterniond>(pose).normalize();
  const double* params[] = {pose};
  std::vector<double> r(n), J(7 * n);
  double* jacobians[] = {J.data()};
  for (auto _ : state) {
    f.Evaluate(params, r.data(), with_jacobian ? jacobians : nullptr);
    benchmark::DoNotOptimize(r.data());
    benchmark::DoNotOptimize(J.data());
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_PlaneFactorEvaluate)->Args({2000, 0})->Args({2000, 1});

void BM_ImuFactorEvaluate(benchmark::State& state) {
  const auto samples = Samples(400.0, 0.2);
  const rvlio::ImuFactor f(
      ImuPreintegration::FromSamples(samples, 0, 100000000, Noise(), Eigen::Vector3d::Zero(),
                                     Eigen::Vector3d::Zero()),
      Eigen::Vector3d(0, 0, -9.81));
  double pi[7] = {0, 0, 0, 1, 0, 0, 0}, pj[7] = {0, 0, 0.05, 1, 0.1, 0, 0};
  Eigen::Map<Eigen::Quaterniond>(pj).normalize();
  double si[9] = {1, 0, 0, 0, 0, 0, 0, 0, 0}, sj[9] = {1, 0, 0, 0, 0, 0, 0, 0, 0};
  const double* params[] = {pi, si, pj, sj};
  double r[15], J0[105], J1[135], J2[105], J3[135];
  double* jacobians[] = {J0, J1, J2, J3};
  for (auto _ : state) {
    f.Evaluate(params, r, jacobians);
    benchmark::DoNotOptimize(r);
    benchmark::DoNotOptimize(J3);
  }
}
BENCHMARK(BM_ImuFactorEvaluate);

void BM_MarginalizeOldestOf10(benchmark::State& state) {
  constexpr int kStates = 10;
  const auto samples = Samples(400.0, 1.2);
  std::vector<std::vector<double>> pose(kStates), sb(kStates, std::vector<double>(9, 0.0));
  rvlio::PoseManifold manifold;
  ceres::Problem::Options po;
  po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  for (int k = 0; k < kStates; ++k) {
    pose[k] = {0, 0, 0, 1, 0.1 * k, 0, 0};
    problem.AddResidualBlock(new rvlio::PlaneFactor(RandomConstraints(2000), rvlio::Pose3(), 0.05),
                             nullptr, pose[k].data());
    problem.SetManifold(pose[k].data(), &manifold);
    if (k == 0) continue;
    const TimeNs t = (k - 1) * 100000000LL;
    problem.AddResidualBlock(
        new rvlio::ImuFactor(ImuPreintegration::FromSamples(samples, t, t + 100000000, Noise(),
                                                            Eigen::Vector3d::Zero(),
                                                            Eigen::Vector3d::Zero()),
                             Eigen::Vector3d(0, 0, -9.81)),
        nullptr, {pose[k - 1].data(), sb[k - 1].data(), pose[k].data(), sb[k].data()});
  }
  for (auto _ : state) {
    rvlio::MarginalizationInfo info;
    info.AddFromProblem(problem, {pose[0].data(), sb[0].data()});
    const rvlio::Status s = info.Marginalize();
    benchmark::DoNotOptimize(s.ok());
  }
}
BENCHMARK(BM_MarginalizeOldestOf10);

}  // namespace

BENCHMARK_MAIN();

// Cost of the RV pass (Alg. 1-3) on one scan's constraint list.
// Target: well under 10 % of a ~3 ms scan update for ~2000
// constraints. BM_ApplyRv includes restoring the list from a copy each
// iteration; BM_CopyList measures that copy alone so it can be subtracted.
#include <cmath>
#include <random>

#include <benchmark/benchmark.h>

#include "rvlio/rv/criterion.h"
#include "rvlio/rv/rv.h"

namespace {

using rvlio::Constraint;
using rvlio::ConstraintList;
using rvlio::Pose3;

Eigen::Vector3d RandomUnit(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
}

// A straight-tunnel scan: wall normals perpendicular to the axis with small
// axial noise, plus ~4 % special constraint vectors from one structure.
ConstraintList TunnelScan(int n, bool degenerate, Pose3* T) {
  std::mt19937 rng(7);
  const Eigen::Vector3d axis = Eigen::Vector3d(1.0, 0.2, 0.05).normalized();
  const Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
  std::normal_distribution<double> spread(0.0, 0.25), axial(0.0, 0.03), az(0.4, 0.2);
  std::uniform_real_distribution<double> pos(-15.0, 15.0), unit(0.0, 1.0);
  *T = Pose3(Eigen::AngleAxisd(0.3, RandomUnit(rng)).toRotationMatrix(), Eigen::Vector3d(5, 1, 2));
  ConstraintList list;
  list.reserve(n);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d u;
    if (!degenerate) {
      u = Eigen::Matrix3d::Identity().col(i % 3);  // three plane families: inactive
    } else if (unit(rng) < 0.04) {
      const double a = 0.6 + 0.4 * unit(rng), f = az(rng);
      u = a * axis + std::sqrt(1 - a * a) * (std::cos(f) * e1 + std::sin(f) * e2);
    } else {
      const double th = static_cast<int>(4 * unit(rng)) * M_PI / 2 + spread(rng);
      u = (std::cos(th) * e1 + std::sin(th) * e2 + axial(rng) * axis).normalized();
    }
    Constraint c;
    c.p_lidar = Eigen::Vector3d(pos(rng), pos(rng), pos(rng));
    c.normal_world = u;
    c.q_world = (*T) * c.p_lidar - 0.05 * u;
    c.residual = 0.05;
    c.weight = 1.0;
    list.push_back(c);
  }
  return list;
}

rvlio::RvOptions PaperSim() {
  rvlio::RvOptions o;
  o.eps0 = 0.510303;
  o.eps1 = 0.11303;
  o.k0 = 695.07;
  return o;
}

void BM_CopyList(benchmark::State& state) {
  Pose3 T;
  const ConstraintList original = TunnelScan(static_cast<int>(state.range(0)), true, &T);
  ConstraintList list = original;
  for (auto _ : state) {
    list = original;
    benchmark::DoNotOptimize(list.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_CopyList)->Arg(500)->Arg(2000)->Arg(8000)->Unit(benchmark::kMicrosecond);

// Full pass on an active (tunnel) scan: criterion, refit, reinforcement, repair.
void BM_ApplyRv(benchmark::State& state) {
  Pose3 T;
  const ConstraintList original = TunnelScan(static_cast<int>(state.range(0)), true, &T);
  ConstraintList list = original;
  rvlio::RvWorkspace ws;
  const rvlio::RvOptions options = PaperSim();
  rvlio::RvReport report;
  for (auto _ : state) {
    list = original;
    report = rvlio::ApplyRv(options, T, &list, &ws);
    benchmark::DoNotOptimize(report);
    benchmark::ClobberMemory();
  }
  state.counters["active"] = report.active;
  state.counters["scv"] = report.num_scv;
  state.counters["repaired"] = report.num_repaired;
  state.counters["iterations"] = report.iterations;
}
BENCHMARK(BM_ApplyRv)->Arg(500)->Arg(2000)->Arg(8000)->Unit(benchmark::kMicrosecond);

// Same, without a reused workspace (allocates the scratch arrays per call).
void BM_ApplyRvNoWorkspace(benchmark::State& state) {
  Pose3 T;
  const ConstraintList original = TunnelScan(static_cast<int>(state.range(0)), true, &T);
  ConstraintList list = original;
  const rvlio::RvOptions options = PaperSim();
  for (auto _ : state) {
    list = original;
    benchmark::DoNotOptimize(rvlio::ApplyRv(options, T, &list));
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_ApplyRvNoWorkspace)->Arg(2000)->Unit(benchmark::kMicrosecond);

// Inactive scan (three plane families): criterion + localizability only; the
// list is not modified, so no copy is needed.
void BM_ApplyRvInactive(benchmark::State& state) {
  Pose3 T;
  ConstraintList list = TunnelScan(static_cast<int>(state.range(0)), false, &T);
  rvlio::RvWorkspace ws;
  rvlio::RvReport report;
  for (auto _ : state) {
    report = rvlio::ApplyRv(PaperSim(), T, &list, &ws);
    benchmark::DoNotOptimize(report);
  }
  state.counters["active"] = report.active;
}
BENCHMARK(BM_ApplyRvInactive)->Arg(2000)->Unit(benchmark::kMicrosecond);

void BM_Criterion(benchmark::State& state) {
  Pose3 T;
  const ConstraintList list = TunnelScan(static_cast<int>(state.range(0)), true, &T);
  rvlio::RvWorkspace ws;
  const rvlio::RvOptions options = PaperSim();
  for (auto _ : state) {
    benchmark::DoNotOptimize(rvlio::EvaluateCriterion(options, list, &ws));
  }
}
BENCHMARK(BM_Criterion)->Arg(2000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();

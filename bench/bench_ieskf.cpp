// IESKF benchmarks: one iterated update (association + RV + solve) of a
// ~2000-point scan against a tunnel-like map, with RV off and on, and the
// per-sample propagation.
#include <random>
#include <string>

#include <benchmark/benchmark.h>

#include "bench_util.h"

#include "rvlio/constraints/plane_association.h"
#include "rvlio/ieskf/ieskf.h"
#include "rvlio/map/voxel_map.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

struct Fixture {
  VoxelMap map{MapOptions()};
  std::vector<Eigen::Vector3d> scan_lidar;
  FilterState truth;
  Fixture() {
    std::mt19937_64 rng(1);
    map.Insert(bench::TunnelPoints(&rng, 0.1, 30.0));
    truth.p_world_imu = Eigen::Vector3d(0.0, 0.5, 3.0);
    const std::vector<Eigen::Vector3d> world = bench::TunnelPoints(&rng, 0.35, 30.0);
    const Pose3 T_imu_world = truth.T_world_imu().Inverse();
    for (size_t i = 0; i < world.size() && scan_lidar.size() < 2000; i += 2)
      scan_lidar.push_back(T_imu_world * world[i]);
  }
};

// One iterated update of 2000 points against the tunnel map from a prior
// 6 cm off. With `cached`, as `rvlio run` does it: the iterations of one
// update share an AssociationCache (constraints.reuse_distance, 5 cm), so the
// iterations after the first search the map again only for points that moved
// farther.
void RunIeskfUpdates(benchmark::State& state, bool cached) {
  static const Fixture fx;
  RvOptions rv;
  rv.enabled = state.range(0) != 0;
  IeskfOptions o;
  o.init_pos_std = 0.1;
  ConstraintOptions co;
  if (!cached) co.reuse_distance = 0.0;
  int iterations = 0;
  for (auto _ : state) {
    AssociationCache cache(co.reuse_distance);
    const AssociateFn associate = [&](const FilterState& x, ConstraintList* out) {
      AssociationStats stats;
      Associate(fx.scan_lidar, x.T_world_imu(), x.T_imu_lidar(), fx.map, co, out, &stats,
                cached ? &cache : nullptr);
    };
    Ieskf f(o, ImuOptions(), co, rv);
    FilterState prior = fx.truth;
    prior.p_world_imu += Eigen::Vector3d(0.05, -0.03, 0.02);
    f.Initialize(prior, 0, ImuSample());
    const IeskfUpdateResult r = f.Update(associate);
    iterations = r.iterations;
    benchmark::DoNotOptimize(r);
  }
  state.counters["iterations"] = iterations;
  state.SetLabel(std::string(rv.enabled ? "rv on" : "rv off") + ", 2000 points" +
                 (cached ? ", cache" : ""));
}

void BM_IeskfUpdate(benchmark::State& state) { RunIeskfUpdates(state, false); }
BENCHMARK(BM_IeskfUpdate)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_IeskfUpdateCached(benchmark::State& state) { RunIeskfUpdates(state, true); }
BENCHMARK(BM_IeskfUpdateCached)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_IeskfPropagate(benchmark::State& state) {
  Ieskf f{IeskfOptions(), ImuOptions(), ConstraintOptions(), RvOptions()};
  f.Initialize(FilterState(), 0, ImuSample());
  ImuSample s;
  s.acc_imu = Eigen::Vector3d(0.1, 0.0, 9.81);
  s.gyro_imu = Eigen::Vector3d(0.01, 0.02, 0.03);
  for (auto _ : state) {
    s.t_ns += 5000000;
    f.Propagate(s);
    if (f.pose_history().size() > 64) f.ClearPoseHistory();
  }
}
BENCHMARK(BM_IeskfPropagate);

}  // namespace
}  // namespace rvlio

BENCHMARK_MAIN();

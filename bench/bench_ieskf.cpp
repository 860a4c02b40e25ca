// IESKF benchmarks: one iterated update (association + RV + solve) of a
// ~2000-point scan against a tunnel-like map, with RV off and on, and the
// per-sample propagation.
#include <random>

#include <benchmark/benchmark.h>

#include "rvlio/constraints/associate.h"
#include "rvlio/ieskf/ieskf.h"
#include "rvlio/map/voxel_map.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

// A 10 x 8 m rectangular tunnel section, 60 m long, with mildly rough walls
// sampled like a 32-beam LiDAR would (dense along rings, sparse across).
std::vector<Eigen::Vector3d> TunnelPoints(std::mt19937_64* rng, double step) {
  std::normal_distribution<double> n(0.0, 0.02);
  std::vector<Eigen::Vector3d> pts;
  for (double x = -30.0; x <= 30.0; x += step) {
    for (double s = -5.0; s <= 5.0; s += step) {
      pts.emplace_back(x, s, 0.0 + n(*rng));
      pts.emplace_back(x, s, 8.0 + n(*rng));
    }
    for (double z = 0.0; z <= 8.0; z += step) {
      pts.emplace_back(x, -5.0 + n(*rng), z);
      pts.emplace_back(x, 5.0 + n(*rng), z);
    }
  }
  return pts;
}

struct Fixture {
  VoxelMap map{MapOptions()};
  std::vector<Eigen::Vector3d> scan_lidar;
  FilterState truth;
  Fixture() {
    std::mt19937_64 rng(1);
    map.Insert(TunnelPoints(&rng, 0.1));
    truth.p_world_imu = Eigen::Vector3d(0.0, 0.5, 3.0);
    const std::vector<Eigen::Vector3d> world = TunnelPoints(&rng, 0.35);
    const Pose3 T_imu_world = truth.T_world_imu().Inverse();
    for (size_t i = 0; i < world.size() && scan_lidar.size() < 2000; i += 2)
      scan_lidar.push_back(T_imu_world * world[i]);
  }
};

void BM_IeskfUpdate(benchmark::State& state) {
  static const Fixture fx;
  RvOptions rv;
  rv.enabled = state.range(0) != 0;
  IeskfOptions o;
  o.init_pos_std = 0.1;
  const AssociateFn associate = [&](const FilterState& x, ConstraintList* out) {
    AssociationStats stats;
    Associate(fx.scan_lidar, x.T_world_imu(), x.T_imu_lidar(), fx.map, ConstraintOptions(), out,
              &stats);
  };
  int iterations = 0;
  for (auto _ : state) {
    Ieskf f(o, ImuOptions(), ConstraintOptions(), rv);
    FilterState prior = fx.truth;
    prior.p_world_imu += Eigen::Vector3d(0.05, -0.03, 0.02);
    f.Initialize(prior, 0, ImuSample());
    const IeskfUpdateResult r = f.Update(associate);
    iterations = r.iterations;
    benchmark::DoNotOptimize(r);
  }
  state.counters["iterations"] = iterations;
  state.SetLabel(rv.enabled ? "rv on, 2000 points" : "rv off, 2000 points");
}
BENCHMARK(BM_IeskfUpdate)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// As `rvlio run` does it: the iterations of one update share an
// AssociationCache (constraints.reuse_distance, 5 cm), so the iterations
// after the first search the map again only for points that moved farther.
void BM_IeskfUpdateCached(benchmark::State& state) {
  static const Fixture fx;
  RvOptions rv;
  rv.enabled = state.range(0) != 0;
  IeskfOptions o;
  o.init_pos_std = 0.1;
  const ConstraintOptions co;
  int iterations = 0;
  for (auto _ : state) {
    AssociationCache cache(co.reuse_distance);
    const AssociateFn associate = [&](const FilterState& x, ConstraintList* out) {
      AssociationStats stats;
      Associate(fx.scan_lidar, x.T_world_imu(), x.T_imu_lidar(), fx.map, co, out, &stats, &cache);
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
  state.SetLabel(rv.enabled ? "rv on, 2000 points, cache" : "rv off, 2000 points, cache");
}
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

// Micro-benchmarks of the association hot path: k-nearest queries, plane
// fits, association of one downsampled scan (~3k points of an OS1-32-like
// sweep in a tunnel) against a ~100k point map, with and without the
// AssociationCache, scan preprocessing, map insertion and removal, and the
// voxel hash lookup (open addressing vs std::unordered_map).
//
//   build/bin/bench_map --benchmark_min_time=0.5
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <tuple>
#include <unordered_map>
#include <vector>

#include <benchmark/benchmark.h>

#include "rvlio/constraints/plane_association.h"
#include "rvlio/constraints/plane_fit.h"
#include "rvlio/lidar/preprocess.h"
#include "rvlio/map/voxel_map.h"

namespace rvlio {
namespace {

// A straight 200 m x 8 m x 5 m tunnel (the paper's weak-feature case).
const Eigen::Vector3d kLo(-100.0, -4.0, 0.0);
const Eigen::Vector3d kHi(100.0, 4.0, 5.0);

double CastInBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double t = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (d(a) > 1e-12) t = std::min(t, (kHi(a) - o(a)) / d(a));
    if (d(a) < -1e-12) t = std::min(t, (kLo(a) - o(a)) / d(a));
  }
  return t;
}

// An OS1-32-like sweep (32 beams, -22.5..22.5 deg, 1024 columns) from o,
// 1 cm range noise, LiDAR frame = world orientation.
Scan Sweep(const Eigen::Vector3d& o, std::mt19937* rng) {
  std::normal_distribution<double> noise(0.0, 0.01);
  Scan scan;
  scan.t_start_ns = 0;
  scan.t_end_ns = 100000000;
  for (int b = 0; b < 32; ++b) {
    const double e = (-22.5 + 45.0 * b / 31) * M_PI / 180;
    for (int c = 0; c < 1024; ++c) {
      const double a = 2 * M_PI * c / 1024;
      const Eigen::Vector3d d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
      const double t = CastInBox(o, d);
      if (t > 100.0) continue;
      LidarPoint p;
      p.p_lidar = ((t + noise(*rng)) * d).cast<float>();
      p.t_ns = scan.t_start_ns + (c * scan.t_end_ns) / 1024;
      p.ring = static_cast<uint16_t>(b);
      scan.points.push_back(p);
    }
  }
  return scan;
}

struct Fixture {
  VoxelMap map;
  Scan raw;
  std::vector<Eigen::Vector3d> scan;  // downsampled, LiDAR frame
  Pose3 T_world_imu;
  Eigen::Vector3d sensor;

  Fixture() {
    std::mt19937 rng(1);
    // Map: sweeps every 0.5 m along 100 m of tunnel, 0.5 m downsampled, as
    // the pipeline inserts them, until the map holds ~100k points.
    LidarOptions lidar;
    ScanPreprocessor pre(lidar);
    Scan down;
    for (double x = -50.0; x <= 50.0 && map.Size() < 100000; x += 0.5) {
      const Eigen::Vector3d o(x, 0.3 * std::sin(x), 2.0);
      pre.Downsample(Sweep(o, &rng), &down);
      for (const LidarPoint& p : down.points) map.InsertPoint(o + p.p_lidar.cast<double>());
    }
    sensor = Eigen::Vector3d(0.25, 0.2, 2.1);
    raw = Sweep(sensor, &rng);
    pre.Downsample(raw, &down);
    for (const LidarPoint& p : down.points) scan.push_back(p.p_lidar.cast<double>());
    // Evaluate at a pose 5 cm / 0.5 deg off, as in an early filter iteration.
    T_world_imu = Pose3(Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
                        sensor + Eigen::Vector3d(0.05, -0.02, 0.01));
  }
};

const Fixture& GetFixture() {
  static const Fixture f;
  return f;
}

void BM_KNearest(benchmark::State& state) {
  const Fixture& f = GetFixture();
  std::vector<Eigen::Vector3d> queries;
  for (const auto& p : f.scan) queries.push_back(f.T_world_imu * p);
  NeighborBuffer nb;
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(f.map.KNearest(queries[i], 5, 2.0, &nb));
    i = (i + 1) % queries.size();
  }
  state.counters["map_points"] = static_cast<double>(f.map.Size());
}
BENCHMARK(BM_KNearest);

void BM_FitLocalPlane(benchmark::State& state) {
  const Fixture& f = GetFixture();
  std::vector<NeighborBuffer> hoods(256);
  for (size_t j = 0; j < hoods.size(); ++j)
    f.map.KNearest(f.T_world_imu * f.scan[j % f.scan.size()], 5, 2.0, &hoods[j]);
  const PlaneThresholds t = PlaneThresholds::From(ConstraintOptions());
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(FitLocalPlane(hoods[i], t));
    i = (i + 1) % hoods.size();
  }
}
BENCHMARK(BM_FitLocalPlane);

void BM_AssociateScan(benchmark::State& state) {
  const Fixture& f = GetFixture();
  ConstraintList constraints;
  AssociationStats stats;
  for (auto _ : state) {
    Associate(f.scan, f.T_world_imu, Pose3(), f.map, ConstraintOptions(), &constraints, &stats);
    benchmark::DoNotOptimize(constraints.data());
  }
  state.counters["scan_points"] = static_cast<double>(f.scan.size());
  state.counters["accepted"] = stats.num_accepted;
  state.counters["map_points"] = static_cast<double>(f.map.Size());
}
BENCHMARK(BM_AssociateScan)->Unit(benchmark::kMillisecond);

// The same association on 1 or 2 threads (constraints.threads): wall time,
// since the second thread's CPU time is not the benchmark thread's.
void BM_AssociateScanThreads(benchmark::State& state) {
  const Fixture& f = GetFixture();
  ConstraintList constraints;
  AssociationStats stats;
  const int threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    Associate(f.scan, f.T_world_imu, Pose3(), f.map, ConstraintOptions(), &constraints, &stats,
              nullptr, threads);
    benchmark::DoNotOptimize(constraints.data());
  }
  state.counters["accepted"] = stats.num_accepted;
}
BENCHMARK(BM_AssociateScanThreads)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

// A later iteration of the same update: the pose moved by ~1 cm, every point
// reuses its plane from the AssociationCache.
void BM_AssociateScanCached(benchmark::State& state) {
  const Fixture& f = GetFixture();
  ConstraintList constraints;
  AssociationStats stats;
  AssociationCache cache(0.05);
  Associate(f.scan, f.T_world_imu, Pose3(), f.map, ConstraintOptions(), &constraints, &stats,
            &cache);
  Pose3 moved = f.T_world_imu;
  int i = 0;
  for (auto _ : state) {
    moved.t.x() = f.T_world_imu.t.x() + ((i++ % 2) ? 0.01 : -0.01);
    Associate(f.scan, moved, Pose3(), f.map, ConstraintOptions(), &constraints, &stats, &cache);
    benchmark::DoNotOptimize(constraints.data());
  }
  state.counters["reused"] = stats.num_reused;
}
BENCHMARK(BM_AssociateScanCached)->Unit(benchmark::kMillisecond);

void BM_PreprocessScan(benchmark::State& state) {
  const Fixture& f = GetFixture();
  ScanPreprocessor pre{LidarOptions()};
  Scan out;
  for (auto _ : state) {
    pre.Downsample(f.raw, &out);
    benchmark::DoNotOptimize(out.points.data());
  }
  state.counters["raw_points"] = static_cast<double>(f.raw.points.size());
  state.counters["kept"] = static_cast<double>(out.points.size());
}
BENCHMARK(BM_PreprocessScan)->Unit(benchmark::kMicrosecond);

void BM_InsertScan(benchmark::State& state) {
  const Fixture& f = GetFixture();
  std::vector<Eigen::Vector3d> world;
  for (const auto& p : f.scan) world.push_back(f.T_world_imu * p);
  for (auto _ : state) {
    state.PauseTiming();
    VoxelMap map = f.map;  // copy: insertion into a full-size map each time
    state.ResumeTiming();
    map.Insert(world);
    benchmark::DoNotOptimize(map.Size());
  }
}
BENCHMARK(BM_InsertScan)->Unit(benchmark::kMicrosecond);

void BM_RemoveFar(benchmark::State& state) {
  const Fixture& f = GetFixture();
  for (auto _ : state) {
    state.PauseTiming();
    VoxelMap map = f.map;
    state.ResumeTiming();
    map.RemoveFar(f.sensor, 30.0);
    benchmark::DoNotOptimize(map.Size());
  }
}
BENCHMARK(BM_RemoveFar)->Unit(benchmark::kMicrosecond);

// The voxel lookup of a query (27 neighbour keys around scan points) in an
// open-addressing table like VoxelMap's vs std::unordered_map with reserve.
std::vector<VoxelKey> LookupKeys(std::vector<VoxelKey>* stored) {
  const Fixture& f = GetFixture();
  std::vector<VoxelKey> keys;
  for (const auto& p : f.scan) {
    const VoxelKey k = KeyOf(f.T_world_imu * p, 1.0);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) keys.push_back(VoxelKey{k.x + dx, k.y + dy, k.z + dz});
  }
  f.map.ForEachPoint([&](const Eigen::Vector3d& p) { stored->push_back(KeyOf(p, 1.0)); });
  std::sort(stored->begin(), stored->end(), [](const VoxelKey& a, const VoxelKey& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  });
  stored->erase(std::unique(stored->begin(), stored->end()), stored->end());
  return keys;
}

void BM_LookupOpenAddressing(benchmark::State& state) {
  std::vector<VoxelKey> stored;
  const std::vector<VoxelKey> keys = LookupKeys(&stored);
  struct Slot {
    VoxelKey key;
    int32_t value = -1;
  };
  size_t cap = 1024;
  while (cap < 2 * stored.size()) cap *= 2;
  std::vector<Slot> table(cap);
  for (size_t i = 0; i < stored.size(); ++i) {
    size_t h = HashVoxelKey(stored[i]) & (cap - 1);
    while (table[h].value >= 0) h = (h + 1) & (cap - 1);
    table[h] = Slot{stored[i], static_cast<int32_t>(i)};
  }
  size_t i = 0;
  for (auto _ : state) {
    const VoxelKey& k = keys[i];
    size_t h = HashVoxelKey(k) & (cap - 1);
    while (table[h].value >= 0 && !(table[h].key == k)) h = (h + 1) & (cap - 1);
    benchmark::DoNotOptimize(table[h].value);
    i = (i + 1) % keys.size();
  }
}
BENCHMARK(BM_LookupOpenAddressing);

void BM_LookupStdUnorderedMap(benchmark::State& state) {
  std::vector<VoxelKey> stored;
  const std::vector<VoxelKey> keys = LookupKeys(&stored);
  std::unordered_map<VoxelKey, int32_t, VoxelKeyHash> table;
  table.reserve(2 * stored.size());
  for (size_t i = 0; i < stored.size(); ++i) table.emplace(stored[i], static_cast<int32_t>(i));
  size_t i = 0;
  for (auto _ : state) {
    auto it = table.find(keys[i]);
    benchmark::DoNotOptimize(it == table.end() ? -1 : it->second);
    i = (i + 1) % keys.size();
  }
}
BENCHMARK(BM_LookupStdUnorderedMap);


void BM_KNearestHot(benchmark::State& state) {
  const Fixture& f = GetFixture();
  std::vector<Eigen::Vector3d> queries;
  for (size_t j = 0; j < 16; ++j) queries.push_back(f.T_world_imu * f.scan[j * 7]);
  NeighborBuffer nb;
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(f.map.KNearest(queries[i], 5, 2.0, &nb));
    i = (i + 1) % queries.size();
  }
}
BENCHMARK(BM_KNearestHot);
}  // namespace
}  // namespace rvlio

BENCHMARK_MAIN();

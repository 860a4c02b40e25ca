// Search structure of a fixed reference cloud (map/reference_map.h): build
// time and memory over a large cloud, then k nearest neighbours (k = 8
// within 0.5 m, what the map evaluation asks) for many query points, one
// thread. Counters: build_s and query_s are thread CPU seconds, memory_MB
// the growth of the resident set while building (run one benchmark per
// process: freed memory is not returned to the system). Candidates: the project's voxel-hash map (ReferenceMap, at two
// voxel sizes), PCL's KdTreeFLANN and nanoflann's KD-tree (when its header
// is installed). Results: docs/map_eval.md.
//
//   build/bin/bench_reference_map --benchmark_filter=/10000000/
//   (the args are reference points / query points)
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include <unistd.h>

#include <benchmark/benchmark.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#if __has_include(<nanoflann.hpp>)
#include <nanoflann.hpp>
#define RVLIO_HAVE_NANOFLANN 1
#endif

#include "rvlio/common/cpu_time.h"
#include "rvlio/map/reference_map.h"

namespace rvlio {
namespace {

constexpr int kK = 8;
constexpr double kRadius = 0.5;

// Resident set size of this process, MB.
double RssMb() {
  long pages = 0, resident = 0;
  FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0.0;
  if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
  std::fclose(f);
  return resident * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1e6;
}

// Points on the wall of a round tunnel of radius 3 m along x, 1.4 cm apart
// on average at 10 M points over 100 m (length grows with n), 2 mm noise
// (a static laser survey); queries: 3 cm noise (a LiDAR map).
std::vector<Eigen::Vector3d> TunnelWall(size_t n, double noise_m, unsigned seed) {
  std::mt19937_64 rng(seed);
  const double length_m = 100.0 * static_cast<double>(n) / 1e7 + 1.0;
  std::uniform_real_distribution<double> along(0.0, length_m), angle(0.0, 2.0 * M_PI);
  std::normal_distribution<double> noise(0.0, noise_m);
  std::vector<Eigen::Vector3d> p(n);
  for (Eigen::Vector3d& x : p) {
    const double a = angle(rng), r = 3.0 + noise(rng);
    x = Eigen::Vector3d(along(rng), r * std::cos(a), r * std::sin(a));
  }
  return p;
}

struct Scene {
  std::vector<Eigen::Vector3d> reference, queries;
};
const Scene& GetScene(size_t n_ref, size_t n_query) {
  static std::unique_ptr<Scene> scene;
  if (!scene || scene->reference.size() != n_ref || scene->queries.size() != n_query) {
    scene.reset();
    scene = std::make_unique<Scene>();
    scene->reference = TunnelWall(n_ref, 0.002, 1);
    // Queries over the same length as the reference.
    scene->queries = TunnelWall(n_query, 0.03, 2);
    const double scale = (100.0 * n_ref / 1e7 + 1.0) / (100.0 * n_query / 1e7 + 1.0);
    for (Eigen::Vector3d& q : scene->queries) q.x() *= scale;
  }
  return *scene;
}

void Report(benchmark::State& state, double build_s, double query_s, double mb, double sum) {
  state.counters["build_s"] = build_s;
  state.counters["query_s"] = query_s;
  state.counters["memory_MB"] = mb;
  state.counters["mean_d"] = sum;
}

// Thread CPU seconds since t0 (ThreadCpuMs): the machine may be shared.
double Seconds(double t0_ms) { return (ThreadCpuMs() - t0_ms) * 1e-3; }

void BM_ReferenceMap(benchmark::State& state, double voxel_m) {
  const Scene& s = GetScene(state.range(0), state.range(1));
  for (auto _ : state) {
    const double rss0 = RssMb();
    double t0 = ThreadCpuMs();
    auto map = std::make_unique<ReferenceMap>(s.reference, ReferenceMapOptions{voxel_m});
    const double build_s = Seconds(t0);
    const double mb = RssMb() - rss0;
    t0 = ThreadCpuMs();
    NeighborBuffer nb;
    double sum = 0.0;
    for (const Eigen::Vector3d& q : s.queries)
      if (map->KNearest(q, kK, kRadius, &nb) > 0) sum += std::sqrt(nb.dist2[0]);
    Report(state, build_s, Seconds(t0), mb, sum / s.queries.size());
  }
}

void BM_PclKdTreeFlann(benchmark::State& state) {
  const Scene& s = GetScene(state.range(0), state.range(1));
  for (auto _ : state) {
    const double rss0 = RssMb();
    double t0 = ThreadCpuMs();
    auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    cloud->reserve(s.reference.size());
    for (const Eigen::Vector3d& p : s.reference)
      cloud->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                     static_cast<float>(p.z())));
    auto tree = std::make_unique<pcl::KdTreeFLANN<pcl::PointXYZ>>(false);  // unsorted radius
    tree->setInputCloud(cloud);
    const double build_s = Seconds(t0);
    const double mb = RssMb() - rss0;
    t0 = ThreadCpuMs();
    std::vector<int> idx(kK);
    std::vector<float> d2(kK);
    double sum = 0.0;
    for (const Eigen::Vector3d& q : s.queries) {
      const pcl::PointXYZ p(static_cast<float>(q.x()), static_cast<float>(q.y()),
                            static_cast<float>(q.z()));
      // k nearest, then the radius test (FLANN's knn has no radius bound).
      if (tree->nearestKSearch(p, kK, idx, d2) > 0 && d2[0] <= kRadius * kRadius)
        sum += std::sqrt(d2[0]);
    }
    Report(state, build_s, Seconds(t0), mb, sum / s.queries.size());
  }
}

#ifdef RVLIO_HAVE_NANOFLANN
struct FloatCloud {
  std::vector<float> xyz;
  size_t kdtree_get_point_count() const { return xyz.size() / 3; }
  float kdtree_get_pt(size_t i, size_t dim) const { return xyz[3 * i + dim]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const { return false; }
};
using NanoTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<float, FloatCloud>, FloatCloud, 3, uint32_t>;

void BM_Nanoflann(benchmark::State& state) {
  const Scene& s = GetScene(state.range(0), state.range(1));
  for (auto _ : state) {
    const double rss0 = RssMb();
    double t0 = ThreadCpuMs();
    auto cloud = std::make_unique<FloatCloud>();
    cloud->xyz.reserve(3 * s.reference.size());
    for (const Eigen::Vector3d& p : s.reference)
      for (int a = 0; a < 3; ++a) cloud->xyz.push_back(static_cast<float>(p(a)));
    // The constructor builds the index (leaves of up to 10 points).
    auto tree = std::make_unique<NanoTree>(3, *cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    const double build_s = Seconds(t0);
    const double mb = RssMb() - rss0;
    t0 = ThreadCpuMs();
    uint32_t idx[kK];
    float d2[kK];
    double sum = 0.0;
    for (const Eigen::Vector3d& q : s.queries) {
      const float p[3] = {static_cast<float>(q.x()), static_cast<float>(q.y()),
                          static_cast<float>(q.z())};
      if (tree->knnSearch(p, kK, idx, d2) > 0 && d2[0] <= kRadius * kRadius)
        sum += std::sqrt(d2[0]);
    }
    Report(state, build_s, Seconds(t0), mb, sum / s.queries.size());
  }
}
#endif

void Sizes(benchmark::internal::Benchmark* b) {
  b->Args({1'000'000, 200'000})->Args({10'000'000, 2'000'000});
  b->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
}

BENCHMARK_CAPTURE(BM_ReferenceMap, voxel_0_1, 0.1)->Apply(Sizes);
BENCHMARK_CAPTURE(BM_ReferenceMap, voxel_0_2, 0.2)->Apply(Sizes);
BENCHMARK(BM_PclKdTreeFlann)->Apply(Sizes);
#ifdef RVLIO_HAVE_NANOFLANN
BENCHMARK(BM_Nanoflann)->Apply(Sizes);
#endif

}  // namespace
}  // namespace rvlio

BENCHMARK_MAIN();

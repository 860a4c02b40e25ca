// The one association routine (constraints/plane_association.h) over the two maps it
// serves: the odometry's working map (VoxelMap) and the leave-one-out map of
// batch refinement (RefineMap, seen by a scan none of whose points it holds).
// Filled with the same points, both must give the same constraints, to the
// bit, and the same statistics: random scenes over several seeds, and a real
// simulated tunnel scan against the map of earlier scans. Also: the same
// constraints for any thread count of the association.
#include <cstdint>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/constraints/plane_association.h"
#include "rvlio/map/voxel_map.h"
#include "rvlio/sim/presets.h"
#include "rvlio/sim/simulator.h"
#include "rvlio/refine/map.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

// A scene: map points (in several scans) and a query scan in its LiDAR frame.
struct Scene {
  std::vector<std::vector<Vector3d>> map_scans;  // world, m
  std::vector<Vector3d> query_lidar;             // LiDAR frame, m
  Pose3 T_world_lidar;
};

Vector3d RandomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vector3d(n(rng), n(rng), n(rng)).normalized();
}

// Points on a few random planes (with noise), on two lines and in clutter,
// so that every outcome of the plane search occurs; the query points are
// drawn the same way plus far outliers.
Scene RandomScene(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-4.0, 4.0), noise(-0.01, 0.01), pick(0.0, 1.0);
  struct Plane { Vector3d n, c; };
  std::vector<Plane> planes;
  for (int i = 0; i < 4; ++i) planes.push_back({RandomUnit(rng), Vector3d(u(rng), u(rng), u(rng))});
  const Vector3d line_dir = RandomUnit(rng), line_c(u(rng), u(rng), u(rng));
  auto sample = [&]() -> Vector3d {
    const double r = pick(rng);
    if (r < 0.75) {
      const Plane& p = planes[rng() % planes.size()];
      const Vector3d a = p.n.unitOrthogonal(), b = p.n.cross(a);
      return p.c + u(rng) * a + u(rng) * b + noise(rng) * p.n;
    }
    if (r < 0.85) return line_c + u(rng) * line_dir + Vector3d(noise(rng), noise(rng), noise(rng));
    return Vector3d(u(rng), u(rng), u(rng));
  };
  Scene s;
  s.map_scans.resize(3);
  for (auto& scan : s.map_scans)
    for (int i = 0; i < 4000; ++i) scan.push_back(sample());
  s.T_world_lidar = Pose3(Eigen::AngleAxisd(u(rng), RandomUnit(rng)).toRotationMatrix(),
                          Vector3d(u(rng), u(rng), u(rng)) * 0.25);
  const Pose3 T_lidar_world = s.T_world_lidar.Inverse();
  for (int i = 0; i < 3000; ++i) {
    Vector3d p = sample() + 0.05 * Vector3d(noise(rng), noise(rng), noise(rng));
    if (i % 50 == 0) p *= 5.0;  // beyond the map: too few neighbours
    s.query_lidar.push_back(T_lidar_world * p);
  }
  return s;
}

void ExpectSameStats(const AssociationStats& a, const AssociationStats& b) {
  EXPECT_EQ(a.num_points, b.num_points);
  EXPECT_EQ(a.num_accepted, b.num_accepted);
  EXPECT_EQ(a.num_too_few_neighbors, b.num_too_few_neighbors);
  EXPECT_EQ(a.num_degenerate, b.num_degenerate);
  EXPECT_EQ(a.num_line_like, b.num_line_like);
  EXPECT_EQ(a.num_not_flat, b.num_not_flat);
  EXPECT_EQ(a.num_far_from_plane, b.num_far_from_plane);
  EXPECT_EQ(a.num_uncertain, b.num_uncertain);
  EXPECT_EQ(a.num_large_residual, b.num_large_residual);
  EXPECT_EQ(a.num_reused, b.num_reused);
  EXPECT_EQ(a.mean_abs_residual, b.mean_abs_residual);
}

void ExpectSameConstraints(const ConstraintList& a, const ConstraintList& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(a[i].p_lidar, b[i].p_lidar);
    EXPECT_EQ(a[i].normal_world, b[i].normal_world);
    EXPECT_EQ(a[i].q_world, b[i].q_world);
    EXPECT_EQ(a[i].residual, b[i].residual);
    EXPECT_EQ(a[i].weight, b[i].weight);
    EXPECT_EQ(a[i].role, b[i].role);
  }
}

// Associates the scene against both maps and compares; returns the
// working map's statistics.
AssociationStats AssociateBoth(const Scene& s, const MapOptions& map_options,
                               const ConstraintOptions& options) {
  VoxelMap voxel_map(map_options);
  RefineMap refine_map(map_options);
  for (size_t k = 0; k < s.map_scans.size(); ++k) {
    voxel_map.Insert(s.map_scans[k]);
    refine_map.Insert(static_cast<int32_t>(k), s.map_scans[k]);
  }
  EXPECT_EQ(static_cast<int64_t>(voxel_map.Size()), refine_map.stats().entries);
  ConstraintList from_voxel, from_refine;
  AssociationStats voxel_stats, refine_stats;
  Associate(s.query_lidar, s.T_world_lidar, Pose3(), voxel_map, options, &from_voxel,
            &voxel_stats);
  // A scan id no map point carries: the leave-one-out map shows every entry.
  const int32_t query_scan = static_cast<int32_t>(s.map_scans.size());
  std::vector<int32_t> sources;
  AssociateScan(s.query_lidar, s.T_world_lidar, query_scan, refine_map, options, &from_refine,
                &refine_stats, &sources);
  ExpectSameConstraints(from_voxel, from_refine);
  ExpectSameStats(voxel_stats, refine_stats);
  EXPECT_EQ(sources.size(), from_refine.size());
  for (int32_t j : sources) EXPECT_TRUE(j >= 0 && j < query_scan);
  return voxel_stats;
}

TEST(MapAgreement, RandomScenesGiveIdenticalConstraintsOnBothMaps) {
  int64_t accepted = 0, line_like = 0, not_flat = 0, far = 0, too_few = 0, large = 0;
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE(seed);
    const Scene scene = RandomScene(seed);
    MapOptions map_options;
    map_options.voxel_size = seed % 2 == 0 ? 0.5 : 1.0;
    map_options.max_points_per_voxel = 10 + static_cast<int>(seed) * 3;
    map_options.min_point_distance = 0.02 * seed;
    ConstraintOptions options;
    options.num_neighbors = 4 + static_cast<int>(seed);
    options.max_neighbor_distance = seed % 3 == 0 ? 0.8 : 2.0;
    options.max_residual = 0.05;
    options.max_normal_std_deg = seed % 2 == 0 ? 5.0 : 0.0;
    const AssociationStats st = AssociateBoth(scene, map_options, options);
    accepted += st.num_accepted;
    line_like += st.num_line_like;
    not_flat += st.num_not_flat;
    far += st.num_far_from_plane;
    too_few += st.num_too_few_neighbors;
    large += st.num_large_residual;
  }
  // The scenes exercise acceptance and the rejections, not one outcome alone.
  EXPECT_GT(accepted, 5000);
  EXPECT_GT(line_like + not_flat + far, 100);
  EXPECT_GT(too_few, 100);
  EXPECT_GT(large, 100);
}

// A tunnel scan of the simulator against the map of five earlier scans, each
// point placed at its true pose (no deskew error), the query at a pose 5 cm
// and 0.3 deg off the truth.
TEST(MapAgreement, SimulatedTunnelScanGivesIdenticalConstraintsOnBothMaps) {
  StatusOr<SimOptions> o = sim::PresetOptions("tunnel");
  ASSERT_TRUE(o.ok());
  auto simulator = sim::Simulator::Create(*o);
  ASSERT_TRUE(simulator.ok()) << simulator.status().message();
  const sim::Simulator& sim = **simulator;
  const Pose3& T_imu_lidar = sim.T_imu_lidar();
  Scene s;
  for (int64_t k = 35; k < 40; ++k) {
    const Scan scan = sim.SimulateScan(k);
    std::vector<Vector3d> p_world;
    for (const LidarPoint& p : scan.points) {
      if (p.p_lidar.squaredNorm() == 0.0f) continue;  // no return
      p_world.push_back(sim.TruthAt(p.t_ns).T_world_imu * T_imu_lidar * p.p_lidar.cast<double>());
    }
    s.map_scans.push_back(std::move(p_world));
  }
  const Scan query = sim.SimulateScan(45);
  for (const LidarPoint& p : query.points)
    if (p.p_lidar.squaredNorm() != 0.0f) s.query_lidar.push_back(p.p_lidar.cast<double>());
  const Pose3 off(Eigen::AngleAxisd(0.3 * M_PI / 180.0, Vector3d(0.3, -0.5, 1.0).normalized())
                      .toRotationMatrix(),
                  Vector3d(0.03, -0.04, 0.0));
  s.T_world_lidar = sim.TruthAt(query.t_end_ns).T_world_imu * off * T_imu_lidar;
  const AssociationStats st = AssociateBoth(s, MapOptions(), ConstraintOptions());
  EXPECT_GT(st.num_accepted, st.num_points / 2);
}

// Association on several threads (AssociateWith's `threads`): fixed chunks of
// points merged in point order, so the constraints, the statistics and the
// AssociationCache are the same, to the bit, for any thread count. Three
// passes per scene as in one IESKF update: a fresh search, a pose 1 cm off
// (most planes reused) and one 20 cm off (most searched again).
TEST(ParallelAssociation, SameConstraintsStatsAndCacheForAnyThreadCount) {
  int64_t reused = 0, searched_again = 0, accepted = 0;
  for (uint32_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE(seed);
    const Scene scene = RandomScene(seed);
    ASSERT_GT(scene.query_lidar.size(), 4u * association_detail::kAssociationChunk);
    MapOptions map_options;
    map_options.voxel_size = seed % 2 == 0 ? 0.5 : 1.0;
    VoxelMap map(map_options);
    for (const auto& scan : scene.map_scans) map.Insert(scan);
    ConstraintOptions options;
    options.max_residual = 0.2;
    const Vector3d shifts[3] = {Vector3d::Zero(), Vector3d(0.01, 0.0, 0.0), Vector3d(0.0, 0.2, 0.0)};
    std::vector<ConstraintList> reference(3);
    std::vector<AssociationStats> reference_stats(3);
    std::vector<AssociationCache::Entry> reference_cache;
    for (int threads : {1, 2, 3, 8}) {
      SCOPED_TRACE(threads);
      AssociationCache cache(0.05);
      for (int pass = 0; pass < 3; ++pass) {
        Pose3 T = scene.T_world_lidar;
        T.t += shifts[pass];
        ConstraintList out;
        AssociationStats stats;
        Associate(scene.query_lidar, T, Pose3(), map, options, &out, &stats, &cache, threads);
        if (threads == 1) {
          reference[pass] = out;
          reference_stats[pass] = stats;
          accepted += stats.num_accepted;
          if (pass == 1) reused += stats.num_reused;
          if (pass == 2) searched_again += stats.num_points - stats.num_reused;
          continue;
        }
        ExpectSameConstraints(reference[pass], out);
        ExpectSameStats(reference_stats[pass], stats);
      }
      if (threads == 1) {
        reference_cache = cache.entries();
        continue;
      }
      ASSERT_EQ(cache.entries().size(), reference_cache.size());
      for (size_t i = 0; i < reference_cache.size(); ++i) {
        EXPECT_EQ(cache.entries()[i].p_world, reference_cache[i].p_world);
        EXPECT_EQ(cache.entries()[i].normal_world, reference_cache[i].normal_world);
        EXPECT_EQ(cache.entries()[i].q_world, reference_cache[i].q_world);
        EXPECT_EQ(cache.entries()[i].outcome, reference_cache[i].outcome);
      }
    }
  }
  EXPECT_GT(accepted, 10000);
  EXPECT_GT(reused, 5000);
  EXPECT_GT(searched_again, 5000);
}

}  // namespace
}  // namespace rvlio

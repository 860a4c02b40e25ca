#include "rvlio/constraints/plane_association.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/math/so3.h"
#include "scene.h"

namespace rvlio {
namespace {

struct RoomFixture {
  test::BoxRoom room{Eigen::Vector3d(-10, -5, 0), Eigen::Vector3d(10, 5, 4)};
  VoxelMap map;
  Pose3 T_world_imu{so3::Exp(Eigen::Vector3d(0.02, -0.03, 0.5)), Eigen::Vector3d(1.0, 0.5, 1.5)};
  Pose3 T_imu_lidar{so3::Exp(Eigen::Vector3d(0.0, 0.05, 0.1)), Eigen::Vector3d(0.1, 0.0, 0.2)};
  std::vector<Eigen::Vector3d> p_lidar;  // scan, LiDAR frame
  std::vector<Eigen::Vector3d> p_world;  // the same points at the true pose

  // A map that covers the walls evenly: small voxels, points in random
  // order so that no voxel fills up from one side.
  static MapOptions DenseMap() {
    MapOptions options;
    options.voxel_size = 0.5;
    options.max_points_per_voxel = 20;
    options.min_point_distance = 0.1;
    return options;
  }

  explicit RoomFixture(uint32_t seed) : map(DenseMap()) {
    std::mt19937 rng(seed);
    std::vector<Eigen::Vector3d> surface = room.SampleSurface(0.08, &rng);
    std::shuffle(surface.begin(), surface.end(), rng);
    map.Insert(surface);
    const Pose3 T_world_lidar = T_world_imu * T_imu_lidar;
    std::normal_distribution<double> n(0.0, 1.0);
    for (int i = 0; i < 3000; ++i) {
      const Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
      const Eigen::Vector3d w = T_world_lidar.t + room.Cast(T_world_lidar.t, dir) * dir;
      p_world.push_back(w);
      p_lidar.push_back(T_world_lidar.Inverse() * w);
    }
  }
};

// Shifting the pose by delta moves every point by delta, so each residual is
// u . delta; a least-squares solve over the constraints recovers delta.
TEST(Associate, ShiftedPoseGivesResidualsEqualToTheOffset) {
  RoomFixture f(1);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::Vector3d delta(u(rng), u(rng), u(rng));
    Pose3 shifted = f.T_world_imu;
    shifted.t += delta;
    ConstraintList constraints;
    AssociationStats stats;
    Associate(f.p_lidar, shifted, f.T_imu_lidar, f.map, ConstraintOptions(), &constraints, &stats);

    EXPECT_EQ(stats.num_points, 3000);
    EXPECT_EQ(stats.num_accepted, static_cast<int>(constraints.size()));
    EXPECT_EQ(stats.num_points, stats.num_accepted + stats.num_too_few_neighbors +
                                    stats.num_degenerate + stats.num_line_like +
                                    stats.num_not_flat + stats.num_far_from_plane +
                                    stats.num_uncertain + stats.num_large_residual);
    EXPECT_GT(stats.num_accepted, 2700);  // only points near edges may fail

    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    int tight = 0;
    for (const Constraint& c : constraints) {
      const Eigen::Vector3d p_true = f.T_world_imu * (f.T_imu_lidar * c.p_lidar);
      const Eigen::Vector3d n_true = f.room.InwardNormal(p_true);
      EXPECT_NEAR(c.normal_world.norm(), 1.0, 1e-12);
      if (std::abs(c.residual - n_true.dot(delta)) < 2e-3) ++tight;
      // Away from edges every neighbour is on the point's own face: the
      // normal is that face's inward normal (oriented towards the sensor) and
      // the residual is exactly the offset along it.
      if (f.room.DistanceToEdge(p_true) > 0.3) {
        EXPECT_GT(c.normal_world.dot(n_true), std::cos(1.0 * M_PI / 180)) << p_true.transpose();
        EXPECT_NEAR(c.residual, n_true.dot(delta), 2e-3);
      }
      EXPECT_NEAR(c.residual, PointToPlaneResidual(c, shifted, f.T_imu_lidar), 1e-9);
      EXPECT_EQ(c.weight, 1.0);
      EXPECT_EQ(c.role, RvRole::kPlain);
      Eigen::Matrix<double, 1, 6> J;
      PointToPlaneResidual(c, f.T_world_imu, f.T_imu_lidar, &J);
      H += J.rightCols<3>().transpose() * J.rightCols<3>();
      b += J.rightCols<3>().transpose() * c.residual;
    }
    EXPECT_GT(tight, 0.98 * constraints.size());
    const Eigen::Vector3d delta_hat = H.ldlt().solve(b);
    EXPECT_LT((delta_hat - delta).norm(), 1e-3)
        << delta_hat.transpose() << " vs " << delta.transpose();
  }
}

TEST(Associate, KeepsPointOrderAndRejectsOutliers) {
  RoomFixture f(3);
  ConstraintOptions options;
  // Points pulled 0.5 m off the walls into the room are outliers for a 0.3 m bound.
  // (Only points 1 m or more from an edge: nearer ones may see another face.)
  std::vector<Eigen::Vector3d> scan = f.p_lidar;
  std::vector<bool> displaced(scan.size(), false);
  const Pose3 T_world_lidar = f.T_world_imu * f.T_imu_lidar;
  int num_displaced = 0;
  for (size_t i = 0; i < scan.size(); i += 3) {
    if (f.room.DistanceToEdge(f.p_world[i]) < 1.0) continue;
    const Eigen::Vector3d n = f.room.InwardNormal(f.p_world[i]);
    scan[i] = T_world_lidar.Inverse() * (f.p_world[i] + 0.5 * n);
    displaced[i] = true;
    ++num_displaced;
  }
  options.max_residual = 0.3;
  options.max_neighbor_distance = 1.0;  // the displaced points still see the wall
  ConstraintList constraints;
  AssociationStats stats;
  Associate(scan, f.T_world_imu, f.T_imu_lidar, f.map, options, &constraints, &stats);
  EXPECT_GT(num_displaced, 500);
  EXPECT_GE(stats.num_large_residual, 0.95 * num_displaced);  // the rest: too few neighbours
  size_t next = 0;
  for (const Constraint& c : constraints) {
    EXPECT_LE(std::abs(c.residual), 0.3);
    // Constraints come in scan order: find each one after the previous.
    while (next < scan.size() && scan[next] != c.p_lidar) ++next;
    ASSERT_LT(next, scan.size()) << "constraint out of order";
    EXPECT_FALSE(displaced[next]);
    ++next;
  }
  // Same input, same output (no hidden state, deterministic).
  ConstraintList again;
  Associate(scan, f.T_world_imu, f.T_imu_lidar, f.map, options, &again, nullptr);
  ASSERT_EQ(again.size(), constraints.size());
  for (size_t i = 0; i < again.size(); ++i) {
    EXPECT_EQ(again[i].p_lidar, constraints[i].p_lidar);
    EXPECT_EQ(again[i].normal_world, constraints[i].normal_world);
    EXPECT_EQ(again[i].residual, constraints[i].residual);
  }
}

void ExpectSame(const ConstraintList& a, const ConstraintList& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].p_lidar, b[i].p_lidar);
    EXPECT_EQ(a[i].normal_world, b[i].normal_world);
    EXPECT_EQ(a[i].q_world, b[i].q_world);
    EXPECT_NEAR(a[i].residual, b[i].residual, 1e-12);
  }
}

TEST(Associate, CacheReusesPlanesOfPointsThatBarelyMoved) {
  RoomFixture f(5);
  const ConstraintOptions options;
  AssociationCache cache(0.05);
  ConstraintList first, fresh, cached;
  AssociationStats stats;
  Associate(f.p_lidar, f.T_world_imu, f.T_imu_lidar, f.map, options, &first, &stats, &cache);
  EXPECT_EQ(stats.num_reused, 0);  // a new scan: everything searched
  Associate(f.p_lidar, f.T_world_imu, f.T_imu_lidar, f.map, options, &fresh, nullptr);
  ExpectSame(first, fresh);

  // Same pose: every point reuses its search, same output.
  Associate(f.p_lidar, f.T_world_imu, f.T_imu_lidar, f.map, options, &cached, &stats, &cache);
  EXPECT_EQ(stats.num_reused, 3000);
  ExpectSame(cached, fresh);

  // 2 cm away: still reused; residuals are those of the kept planes at the
  // new pose, and nearly every constraint equals a fresh search's.
  Pose3 moved = f.T_world_imu;
  moved.t += Eigen::Vector3d(0.015, -0.01, 0.008);
  Associate(f.p_lidar, moved, f.T_imu_lidar, f.map, options, &cached, &stats, &cache);
  EXPECT_EQ(stats.num_reused, 3000);
  for (const Constraint& c : cached)
    EXPECT_NEAR(c.residual, PointToPlaneResidual(c, moved, f.T_imu_lidar), 1e-9);
  Associate(f.p_lidar, moved, f.T_imu_lidar, f.map, options, &fresh, nullptr);
  EXPECT_NEAR(static_cast<double>(cached.size()), static_cast<double>(fresh.size()), 30.0);

  // 20 cm away: searched again, identical to a fresh association there.
  moved.t += Eigen::Vector3d(0.2, 0.0, 0.0);
  Associate(f.p_lidar, moved, f.T_imu_lidar, f.map, options, &cached, &stats, &cache);
  EXPECT_EQ(stats.num_reused, 0);
  Associate(f.p_lidar, moved, f.T_imu_lidar, f.map, options, &fresh, nullptr);
  ExpectSame(cached, fresh);

  // Another scan size resets the cache; so does Reset().
  std::vector<Eigen::Vector3d> shorter(f.p_lidar.begin(), f.p_lidar.begin() + 100);
  Associate(shorter, moved, f.T_imu_lidar, f.map, options, &cached, &stats, &cache);
  EXPECT_EQ(stats.num_reused, 0);
  cache.Reset();
  Associate(shorter, moved, f.T_imu_lidar, f.map, options, &cached, &stats, &cache);
  EXPECT_EQ(stats.num_reused, 0);
}

TEST(Associate, EmptyMapGivesNoConstraints) {
  RoomFixture f(4);
  VoxelMap empty;
  ConstraintList constraints(3);  // cleared by Associate
  AssociationStats stats;
  Associate(f.p_lidar, f.T_world_imu, f.T_imu_lidar, empty, ConstraintOptions(), &constraints,
            &stats);
  EXPECT_TRUE(constraints.empty());
  EXPECT_EQ(stats.num_too_few_neighbors, 3000);
  EXPECT_EQ(stats.mean_abs_residual, 0.0);
}

}  // namespace
}  // namespace rvlio

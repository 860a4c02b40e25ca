// Alg. 3 repair with the in-plane reading of Eq. (20).
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "rv_test_util.h"
#include "rvlio/rv/repair.h"
#include "rvlio/rv/rv.h"

namespace rvlio {
namespace {

using test::RandomUnit;

TEST(RepairTest, ProjectionRemovesTheOutOfPlaneComponent) {
  std::mt19937 rng(41);
  for (int trial = 0; trial < 1000; ++trial) {
    const Eigen::Vector3d n = RandomUnit(rng), u = RandomUnit(rng);
    Eigen::Vector3d u_repaired;
    ASSERT_TRUE(ProjectIntoPlane(u, n, &u_repaired));
    EXPECT_NEAR(u_repaired.dot(n), 0.0, 1e-12);
    EXPECT_NEAR(u_repaired.norm(), 1.0, 1e-12);
    // It is the unit vector of plane alpha closest to u (and not (u.n) n).
    const Eigen::Vector3d in_plane = u - u.dot(n) * n;
    EXPECT_NEAR(u_repaired.dot(in_plane), in_plane.norm(), 1e-12);
    EXPECT_GE(u_repaired.dot(u), 0.0);
    // Already in the plane: unchanged.
    Eigen::Vector3d again;
    ASSERT_TRUE(ProjectIntoPlane(u_repaired, n, &again));
    EXPECT_LT((again - u_repaired).norm(), 1e-12);
  }
}

TEST(RepairTest, VectorAlongTheNormalIsNotRepaired) {
  const Eigen::Vector3d n = Eigen::Vector3d(1, 2, 3).normalized();
  Eigen::Vector3d out(7, 7, 7);
  EXPECT_FALSE(ProjectIntoPlane(n, n, &out));
  EXPECT_FALSE(ProjectIntoPlane(-n, n, &out));
  EXPECT_EQ(out, Eigen::Vector3d(7, 7, 7));
}

TEST(RepairTest, RepairsExactlyTheCoplanarVectorsWithinEps1AtThePose) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> eps1(0.005, 0.1);
  for (int trial = 0; trial < 200; ++trial) {
    test::TunnelSpec spec;
    spec.num_coplanar = 1000;
    spec.num_scv = trial % 80;
    spec.axial_noise = 0.03;  // some walls beyond eps1, some within
    const test::TunnelSet set = test::MakeTunnelSet(rng, spec);
    RvOptions options;
    options.reinforce = trial % 2 == 0;
    options.eps1 = eps1(rng);
    ConstraintList list = set.list;
    const RvReport report = ApplyRv(options, set.T_world_lidar, &list);
    ASSERT_TRUE(report.active);
    const Eigen::Vector3d n = report.n_alpha;
    int expected_repaired = 0;
    for (size_t i = 0; i < list.size(); ++i) {
      const Eigen::Vector3d u = set.list[i].normal_world;
      const double d = std::abs(u.dot(n));
      const bool repair = !set.is_scv[i] && d <= options.eps1;
      expected_repaired += repair;
      const Constraint& c = list[i];
      if (repair) {
        ASSERT_EQ(c.role, RvRole::kRepaired) << i;
        EXPECT_NEAR(c.normal_world.dot(n), 0.0, 1e-12);
        EXPECT_NEAR(c.normal_world.norm(), 1.0, 1e-12);
        EXPECT_LT((c.normal_world - (u - u.dot(n) * n).normalized()).norm(), 1e-12);
        // Residual of Eq. (3) at the pose with the repaired normal.
        const Eigen::Vector3d p_world = set.T_world_lidar.R * c.p_lidar + set.T_world_lidar.t;
        EXPECT_NEAR(c.residual, c.normal_world.dot(p_world - c.q_world), 1e-9);
        EXPECT_EQ(c.weight, set.list[i].weight);
        // |r' - r| = |(u' - u) . (p - q)| <= |u' - u| |p - q| (Cauchy-Schwarz).
        EXPECT_LE(std::abs(c.residual - set.list[i].residual),
                  (c.normal_world - u).norm() * (p_world - c.q_world).norm() + 1e-12);
      } else {
        EXPECT_NE(c.role, RvRole::kRepaired);
        EXPECT_EQ(c.normal_world, u);
        EXPECT_EQ(c.residual, set.list[i].residual);
      }
    }
    EXPECT_EQ(report.num_repaired, expected_repaired);
    EXPECT_GT(expected_repaired, 0);
    // The repaired wall normals carry no axial information any more.
    for (const Constraint& c : list) {
      if (c.role == RvRole::kRepaired) {
        EXPECT_NEAR(c.normal_world.dot(set.axis), 0.0, 0.05);
      }
    }
  }
}

TEST(RepairTest, ResidualIsRecomputedAtTheGivenPoseNotCopied) {
  std::mt19937 rng(43);
  test::TunnelSpec spec;
  spec.num_coplanar = 300;
  spec.num_scv = 5;
  const test::TunnelSet set = test::MakeTunnelSet(rng, spec);
  RvOptions options;
  options.eps1 = 0.5;
  Pose3 other = set.T_world_lidar;
  other.t += Eigen::Vector3d(0.3, -0.2, 0.1);
  ConstraintList a = set.list, b = set.list;
  ApplyRv(options, set.T_world_lidar, &a);
  ApplyRv(options, other, &b);
  int checked = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].role != RvRole::kRepaired) continue;
    ASSERT_EQ(b[i].role, RvRole::kRepaired);
    EXPECT_NEAR(b[i].residual - a[i].residual,
                a[i].normal_world.dot(Eigen::Vector3d(0.3, -0.2, 0.1)), 1e-9);
    ++checked;
  }
  EXPECT_GT(checked, 250);
}

}  // namespace
}  // namespace rvlio

#include "rvlio/constraints/reference_surface.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/constraints/plane_association.h"

namespace rvlio {
namespace {

// Random points on the plane z = 0 over [-1, 1]^2.
std::vector<Eigen::Vector3d> Plane(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Vector3d> p(n);
  for (Eigen::Vector3d& x : p) x = Eigen::Vector3d(u(rng), u(rng), 0.0);
  return p;
}

TEST(ReferenceSurface, SignedDistanceToThePlaneOrientedTowardsTheViewPoint) {
  const ReferenceMap ref(Plane(20000, 1));
  NeighborBuffer nb;
  const SurfaceQueryOptions options;
  const Eigen::Vector3d q(0.1, -0.2, 0.02);
  const Eigen::Vector3d above(0.0, 0.0, 5.0), below(0.0, 0.0, -5.0);
  const SurfaceDistance up = QueryReferenceSurface(ref, q, options, &nb, &above);
  ASSERT_TRUE(up.has_surface());
  EXPECT_NEAR(up.signed_m, 0.02, 1e-6);
  EXPECT_NEAR(up.normal.z(), 1.0, 1e-9);
  EXPECT_GE(up.nearest_m, 0.02);
  EXPECT_EQ(up.num_neighbors, options.num_neighbors);
  const SurfaceDistance down = QueryReferenceSurface(ref, q, options, &nb, &below);
  EXPECT_NEAR(down.signed_m, -0.02, 1e-6);
  const SurfaceDistance unsigned_d = QueryReferenceSurface(ref, q, options, &nb);
  EXPECT_NEAR(unsigned_d.signed_m, 0.02, 1e-6);
}

TEST(ReferenceSurface, NoSurfaceBeyondTheSearchRadius) {
  const ReferenceMap ref(Plane(5000, 2));
  NeighborBuffer nb;
  SurfaceQueryOptions options;
  options.search_radius = 0.3;
  const SurfaceDistance far = QueryReferenceSurface(ref, Eigen::Vector3d(3.0, 0, 0), options, &nb);
  EXPECT_FALSE(far.has_surface());
  EXPECT_TRUE(std::isnan(far.nearest_m));
  EXPECT_TRUE(std::isnan(far.signed_m));
  // Near the edge: a nearest point, but fewer than k within the radius.
  options.num_neighbors = 20;
  options.search_radius = 0.05;
  const SurfaceDistance edge =
      QueryReferenceSurface(ref, Eigen::Vector3d(1.04, 0.0, 0.0), options, &nb);
  EXPECT_FALSE(edge.has_surface());
  EXPECT_EQ(edge.status, PlaneStatus::kTooFewPoints);
}

TEST(ReferenceSurface, LineLikeReferenceHasNoSurface) {
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 200; ++i) line.emplace_back(0.01 * i, 0.0, 0.0);
  const ReferenceMap ref(line);
  NeighborBuffer nb;
  const SurfaceDistance d =
      QueryReferenceSurface(ref, Eigen::Vector3d(1.0, 0.05, 0.0), SurfaceQueryOptions(), &nb);
  EXPECT_NEAR(d.nearest_m, 0.05, 1e-6);
  EXPECT_EQ(d.status, PlaneStatus::kLineLike);
  EXPECT_TRUE(std::isnan(d.signed_m));
}

// The association runs against a ReferenceMap through NeighborSearchTraits
// exactly as against the working map (localization in a prior map).
TEST(ReferenceSurface, AssociationSearchesAReferenceMapLikeTheVoxelMap) {
  const std::vector<Eigen::Vector3d> plane = Plane(20000, 3);
  const ReferenceMap ref(plane);
  MapOptions mo;
  mo.max_points_per_voxel = 65535;
  mo.min_point_distance = 0.0;
  VoxelMap voxels(mo);
  voxels.Insert(plane);
  std::vector<Eigen::Vector3d> scan;
  for (int i = 0; i < 50; ++i) scan.emplace_back(-0.5 + 0.02 * i, 0.1, -1.97);
  Pose3 T_world_lidar;
  T_world_lidar.t = Eigen::Vector3d(0.0, 0.0, 2.0);
  ConstraintList from_ref, from_voxels;
  AssociationStats s_ref, s_voxels;
  AssociateWith(scan, T_world_lidar, ref, ConstraintOptions(), &from_ref, &s_ref);
  AssociateWith(scan, T_world_lidar, voxels, ConstraintOptions(), &from_voxels, &s_voxels);
  EXPECT_GT(s_ref.num_accepted, 30);  // some 5-point neighbourhoods are line-like
  EXPECT_EQ(s_ref.num_accepted, s_voxels.num_accepted);
  EXPECT_EQ(s_ref.num_line_like, s_voxels.num_line_like);
  ASSERT_EQ(from_ref.size(), from_voxels.size());
  for (size_t i = 0; i < from_ref.size(); ++i) {
    EXPECT_NEAR(from_ref[i].residual, 0.03, 1e-6);
    EXPECT_EQ(from_ref[i].residual, from_voxels[i].residual);
  }
}

}  // namespace
}  // namespace rvlio

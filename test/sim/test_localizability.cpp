// The simulator's true localizability (sim/localizability.h): the analytic
// normals of every shape, the information of hand-built normal sets, and a
// whole simulated scan of the planar tunnel (featureless preset, no
// roughness) against an independent computation from the analytic faces.
#include <cmath>
#include <memory>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "rvlio/sim/localizability.h"
#include "rvlio/sim/presets.h"
#include "rvlio/sim/simulator.h"

namespace rvlio::sim {
namespace {

TEST(SurfaceNormal, BoxSidesAreOutwardAndRotated) {
  Box box;
  box.center = Eigen::Vector3d(1, 2, 3);
  box.R_world_box = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  box.half = Eigen::Vector3d(0.5, 1.0, 2.0);
  for (int axis = 0; axis < 3; ++axis)
    for (double sign : {-1.0, 1.0}) {
      Eigen::Vector3d local(0.2, -0.3, 0.4);
      local[axis] = sign * box.half[axis];
      const Eigen::Vector3d p = box.center + box.R_world_box * local;
      const Eigen::Vector3d expected = box.R_world_box.col(axis) * sign;
      EXPECT_LT((box.Normal(p) - expected).norm(), 1e-12) << axis << " " << sign;
    }
}

TEST(SurfaceNormal, CylinderMantleAndDiscs) {
  Cylinder c;
  c.center = Eigen::Vector3d(0, 0, 1);
  c.axis = Eigen::Vector3d(0, 1, 1).normalized();
  c.radius = 0.5;
  c.half_length = 2.0;
  const Eigen::Vector3d across = Eigen::Vector3d::UnitX();
  EXPECT_LT((c.Normal(c.center + 0.5 * across + 0.7 * c.axis) - across).norm(), 1e-12);
  EXPECT_LT((c.Normal(c.center + 0.2 * across + 2.0 * c.axis) - c.axis).norm(), 1e-12);
  EXPECT_LT((c.Normal(c.center - 0.2 * across - 2.0 * c.axis) + c.axis).norm(), 1e-12);
}

// The normal of a rough face is the normalized gradient of
// p[axis] - offset - h(u, v): checked against central differences of h.
TEST(SurfaceNormal, RoughFaceMatchesNumericGradient) {
  Face f;
  f.axis = 1;
  f.offset = 2.0;
  f.bounds = {-100, 100, -100, 100};
  f.relief = HeightField({{0.05, 2.0, 1.0, 0.3}, {0.02, -1.0, 3.0, 1.1}});
  const double u = 0.7, v = -1.3, e = 1e-6;  // u = z, v = x for axis y
  const double du = (f.relief.Height(u + e, v) - f.relief.Height(u - e, v)) / (2 * e);
  const double dv = (f.relief.Height(u, v + e) - f.relief.Height(u, v - e)) / (2 * e);
  const Eigen::Vector3d expected = Eigen::Vector3d(-dv, 1.0, -du).normalized();
  const Eigen::Vector3d p(v, f.offset + f.relief.Height(u, v), u);
  EXPECT_LT((f.Normal(p) - expected).norm(), 1e-8);
}

// A preset, shortened, and its simulator.
std::unique_ptr<Simulator> Simulate(const char* preset, double duration_s, int columns,
                                    double range_noise_m, SimOptions* o) {
  *o = *PresetOptions(preset);
  o->duration = duration_s;
  o->lidar.columns = columns;
  o->lidar.range_noise = range_noise_m;
  auto sim = Simulator::Create(*o);
  return sim.ok() ? std::move(*sim) : nullptr;
}

SurfaceHit Hit(const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
  SurfaceHit h;
  h.p_world = p;
  h.normal_world = n.normalized();
  h.returned = true;
  return h;
}

// A corridor (two walls and a floor) leaves the axis x unconstrained; a
// room (plus end walls) none. Per-point normalization: the eigenvalues sum 1.
TEST(Localizability, CorridorIsDegenerateAlongItsAxisRoomIsNot) {
  std::vector<SurfaceHit> hits;
  for (int i = 0; i < 10; ++i) {
    hits.push_back(Hit({i * 1.0, 2, 0.1 * i}, {0, -1, 0}));
    hits.push_back(Hit({i * 1.0, -2, 0.5 - 0.2 * i}, {0, 1, 0}));
    hits.push_back(Hit({i * 1.0, 0.3 * i - 1.5, -1}, {0, 0, 1}));
  }
  hits.push_back(SurfaceHit());  // no return: skipped
  std::vector<int> all(hits.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  const ScanLocalizability corridor = LocalizabilityOf(hits, all, 0.02);
  EXPECT_EQ(corridor.points, 30);
  EXPECT_NEAR(corridor.eigenvalues[0], 0.0, 1e-12);
  EXPECT_NEAR(corridor.eigenvalues[1], 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(corridor.eigenvalues[2], 2.0 / 3.0, 1e-12);
  EXPECT_LT((corridor.weak_dir_world - Eigen::Vector3d::UnitX()).norm(), 1e-9);
  EXPECT_TRUE(corridor.degenerate);
  EXPECT_NEAR(corridor.pose_eigenvalue_min, 0.0, 1e-9);
  EXPECT_NEAR(std::abs(corridor.pose_weak[3]), 1.0, 1e-6);  // pure translation along x

  for (int i = 0; i < 10; ++i) hits.push_back(Hit({5, 0.1 * i, 1}, {-1, 0, 0}));
  all.resize(hits.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  const ScanLocalizability room = LocalizabilityOf(hits, all, 0.02);
  EXPECT_EQ(room.points, 40);
  EXPECT_NEAR(room.eigenvalues.sum(), 1.0, 1e-12);
  EXPECT_NEAR(room.eigenvalues[0], 0.25, 1e-12);
  EXPECT_NEAR(room.ratio, 0.5, 1e-12);
  EXPECT_FALSE(room.degenerate);
}

// Every kept point of a planar-tunnel scan lies on one of the analytic faces;
// their axes give the information without ray hit records: lambda along x is
// 0 (the tunnel's axis), along y and z the fractions of wall and of
// floor/ceiling points.
TEST(Localizability, PlanarTunnelScanMatchesAnalyticFaces) {
  SimOptions o;
  const auto sim = Simulate("featureless", 6.0, 1024, 0.0, &o);
  ASSERT_TRUE(sim);
  const World& world = sim->world();
  ASSERT_TRUE(world.boxes().empty() && world.cylinders().empty());
  LocalizabilityTruth truth(o.localizability, o.lidar);
  LidarOptions grid;
  grid.min_range = o.lidar.min_range;
  grid.max_range = o.lidar.max_range;
  grid.voxel_size = o.localizability.voxel_size;
  ScanPreprocessor preprocessor(grid);
  for (int64_t k : {0, 45}) {
    std::vector<SurfaceHit> hits;
    const Scan scan = sim->SimulateScan(k, &hits);
    const ScanLocalizability l = truth.Compute(world, scan, &hits);
    std::vector<int> kept;
    preprocessor.SelectIndices(scan, &kept);
    Eigen::Vector3d count = Eigen::Vector3d::Zero();
    for (int i : kept) {
      const Eigen::Vector3d& p = hits[static_cast<size_t>(i)].p_world;
      int on = -1;
      for (const Face& f : world.faces())
        if (f.Covers(p[f.UAxis()], p[f.VAxis()]) && std::abs(p[f.axis] - f.offset) < 1e-6)
          on = f.axis;
      ASSERT_GE(on, 0) << p.transpose();
      count[on] += 1.0;
    }
    ASSERT_EQ(l.points, static_cast<int>(kept.size()));
    ASSERT_GT(l.points, 500);
    EXPECT_EQ(count.x(), 0.0);
    const Eigen::Vector3d expected = count / count.sum();  // diagonal information
    EXPECT_NEAR(l.eigenvalues[0], 0.0, 1e-12);
    EXPECT_NEAR(l.eigenvalues[1], std::min(expected.y(), expected.z()), 1e-12);
    EXPECT_NEAR(l.eigenvalues[2], std::max(expected.y(), expected.z()), 1e-12);
    EXPECT_LT((l.weak_dir_world - Eigen::Vector3d::UnitX()).norm(), 1e-9);
    EXPECT_TRUE(l.degenerate);
    EXPECT_EQ(l.t_ns, scan.t_end_ns);
  }
}

// A closed hall constrains every direction: no scan degenerate.
TEST(Localizability, HallScansAreWellConstrained) {
  SimOptions o;
  const auto sim = Simulate("hall", 10.0, 512, 0.03, &o);
  ASSERT_TRUE(sim);
  LocalizabilityTruth truth(o.localizability, o.lidar);
  for (int64_t k : {0, 40, 90}) {
    std::vector<SurfaceHit> hits;
    const Scan scan = sim->SimulateScan(k, &hits);
    const ScanLocalizability l = truth.Compute(sim->world(), scan, &hits);
    EXPECT_GT(l.ratio, 0.2) << k;
    EXPECT_FALSE(l.degenerate) << k;
    EXPECT_NEAR(l.eigenvalues.sum(), 1.0, 1e-9);
  }
}

}  // namespace
}  // namespace rvlio::sim

// Deviation of a map from the reference (odometry/deviation.h).
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/odometry/deviation.h"

namespace rvlio {
namespace {

// A wall at y = 3 m (x 0..20 m, z 0..4 m) every step_m; with `bulge_m`, the
// part 8 <= x < 12 is moved that far towards y = 0 (a convergence).
std::vector<Eigen::Vector3d> Wall(double step_m, double bulge_m) {
  std::vector<Eigen::Vector3d> p;
  for (double x = 0.0; x < 20.0; x += step_m)
    for (double z = 0.0; z <= 4.0; z += step_m)
      p.emplace_back(x, 3.0 - (x >= 8.0 && x < 12.0 ? bulge_m : 0.0), z);
  return p;
}

// `count` poses 0.1 s apart from `start` in steps of `step` (m).
Trajectory Line(const Eigen::Vector3d& start, const Eigen::Vector3d& step, int count) {
  Trajectory t;
  for (int i = 0; i < count; ++i) {
    StampedPose s;
    s.t_ns = i * 100000000LL;
    s.p_world_imu = start + i * step;
    t.push_back(s);
  }
  return t;
}

Trajectory AlongX() { return Line(Eigen::Vector3d(0.0, 0.0, 1.5), Eigen::Vector3d::UnitX(), 21); }

TEST(Deviation, AConvergenceShowsAtItsChainageWithItsSign) {
  const ReferenceMap reference(Wall(0.05, 0.0));
  const std::vector<Eigen::Vector3d> p_map = Wall(0.2, 0.05);
  const PointDeviations d = ComputeDeviations(p_map, reference, AlongX(), SurfaceQueryOptions());
  ASSERT_EQ(d.deviation_m.size(), p_map.size());
  const std::vector<DeviationBin> bins = BinByChainage(d, 1.0);
  ASSERT_GE(bins.size(), 19u);
  for (const DeviationBin& b : bins) {
    if (b.count == 0) continue;
    // Bins wholly inside / outside the convergence (its edges are at 8 and 12 m).
    if (b.chainage_m >= 8.0 && b.chainage_m < 11.0) {
      EXPECT_NEAR(b.median_m, 0.05, 0.002) << b.chainage_m;
    }
    if (b.chainage_m < 7.0 || b.chainage_m >= 13.0) {
      EXPECT_LT(b.median_abs_m, 0.002) << b.chainage_m;
    }
    EXPECT_GE(b.max_abs_m, b.p95_abs_m);
    EXPECT_GE(b.p95_abs_m, b.median_abs_m);
  }
}

TEST(Deviation, NoReferenceSurfaceGivesNaN) {
  const ReferenceMap reference(Wall(0.05, 0.0));
  const std::vector<Eigen::Vector3d> p_map = {Eigen::Vector3d(5.0, 3.0, 2.0),
                                              Eigen::Vector3d(5.0, -3.0, 2.0)};  // no wall there
  const PointDeviations d = ComputeDeviations(p_map, reference, AlongX(), SurfaceQueryOptions());
  EXPECT_NEAR(d.deviation_m[0], 0.0, 1e-3);
  EXPECT_TRUE(std::isnan(d.deviation_m[1]));
  EXPECT_NEAR(d.chainage_m[1], 5.0, 0.3);
  const std::vector<DeviationBin> bins = BinByChainage(d, 1.0);
  ASSERT_EQ(bins.size(), 6u);
  EXPECT_EQ(bins[5].count, 1);
  EXPECT_EQ(bins[0].count, 0);
  EXPECT_TRUE(std::isnan(bins[0].median_m));
}

// A box tunnel around the flight along x (walls at y = +-3 m, floor z = 0,
// ceiling z = 4 m, x 0..20 m), every step_m; with `bulge_m` the left wall
// (y = +3) moves that far inwards for 8 <= x < 12 (a convergence).
std::vector<Eigen::Vector3d> Box(double step_m, double bulge_m) {
  std::vector<Eigen::Vector3d> p;
  for (double x = 0.0; x < 20.0; x += step_m) {
    const double left_y = 3.0 - (x >= 8.0 && x < 12.0 ? bulge_m : 0.0);
    for (double z = 0.2; z <= 3.8; z += step_m) {
      p.emplace_back(x, left_y, z);
      p.emplace_back(x, -3.0, z);
    }
    for (double y = -2.8; y <= 2.8; y += step_m) {
      p.emplace_back(x, y, 0.0);
      p.emplace_back(x, y, 4.0);
    }
  }
  return p;
}

TEST(Deviation, EachSurfaceOfTheTunnelHasItsOwnStatistics) {
  const ReferenceMap reference(Box(0.05, 0.0));
  const std::vector<Eigen::Vector3d> p_map = Box(0.2, 0.05);
  const PointDeviations d = ComputeDeviations(p_map, reference, AlongX(), SurfaceQueryOptions());
  ASSERT_EQ(d.side.size(), p_map.size());
  // The flight goes along +x with +z up: +y is on its left.
  for (size_t i = 0; i < p_map.size(); ++i) {
    const Eigen::Vector3d& p = p_map[i];
    const TunnelSide want = p.z() == 0.0   ? TunnelSide::kFloor
                            : p.z() == 4.0 ? TunnelSide::kCeiling
                            : p.y() > 0.0  ? TunnelSide::kLeft
                                           : TunnelSide::kRight;
    ASSERT_EQ(d.side[i], want) << p.transpose();
  }
  const std::vector<DeviationBin> bins = BinByChainage(d, 1.0);
  ASSERT_GE(bins.size(), 19u);
  const auto side = [](const DeviationBin& b, TunnelSide s) { return b.sides[static_cast<int>(s)]; };
  const DeviationBin& in = bins[9];  // wholly inside the convergence
  EXPECT_NEAR(side(in, TunnelSide::kLeft).median_m, 0.05, 0.002);
  EXPECT_NEAR(side(in, TunnelSide::kLeft).p95_abs_m, 0.05, 0.002);
  for (TunnelSide s : {TunnelSide::kRight, TunnelSide::kFloor, TunnelSide::kCeiling}) {
    EXPECT_LT(std::abs(side(in, s).median_m), 0.002) << TunnelSideName(s);
    EXPECT_GT(side(in, s).count, 0) << TunnelSideName(s);
  }
  // The four surfaces' counts make up the bin's (every point has a side here).
  int sum = 0;
  for (const DeviationBin::Side& s : in.sides) sum += s.count;
  EXPECT_EQ(sum, in.count);
  // The bin's median of all four surfaces hides the one wall that moved.
  EXPECT_LT(std::abs(in.median_m), 0.01);
  EXPECT_NEAR(side(bins[3], TunnelSide::kLeft).median_m, 0.0, 0.002);
}

TEST(Deviation, AVerticalTrajectoryHasNoSides) {
  const Trajectory up = Line(Eigen::Vector3d(5.0, 0.0, 0.0), 0.5 * Eigen::Vector3d::UnitZ(), 11);
  const ReferenceMap reference(Wall(0.05, 0.0));
  const PointDeviations d =
      ComputeDeviations({Eigen::Vector3d(5.0, 3.0, 2.0)}, reference, up, SurfaceQueryOptions());
  EXPECT_EQ(d.side[0], TunnelSide::kNone);
  const std::vector<DeviationBin> bins = BinByChainage(d, 1.0);
  ASSERT_FALSE(bins.empty());
  EXPECT_EQ(bins.back().count, 1);
  for (const DeviationBin::Side& s : bins.back().sides) {
    EXPECT_EQ(s.count, 0);
    EXPECT_TRUE(std::isnan(s.median_m));
  }
}

}  // namespace
}  // namespace rvlio

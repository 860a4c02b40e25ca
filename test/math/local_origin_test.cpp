// The local frame of data in a user's frame (math/local_origin.h): the
// origin is the data's rounded median, and moving data in and out is exact
// enough to keep millimetres at a national grid's coordinates.
#include "rvlio/math/local_origin.h"

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace rvlio {
namespace {

const Eigen::Vector3d kUtm(500000.0, 5400000.0, 0.0);  // easting, northing, height (m)

std::vector<Eigen::Vector3d> Cloud(const Eigen::Vector3d& centre, double half_extent_m, int n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-half_extent_m, half_extent_m);
  std::vector<Eigen::Vector3d> p(n);
  for (Eigen::Vector3d& x : p) x = centre + Eigen::Vector3d(u(rng), u(rng), u(rng));
  return p;
}

TEST(LocalOrigin, DataNearZeroKeepTheUserFrame) {
  EXPECT_TRUE(ChooseLocalOrigin(Cloud(Eigen::Vector3d(120.0, -40.0, 3.0), 60.0, 1000)).IsZero());
  EXPECT_TRUE(ChooseLocalOrigin(std::vector<Eigen::Vector3d>()).IsZero());
  EXPECT_TRUE(ChooseLocalOrigin(Trajectory()).IsZero());
}

TEST(LocalOrigin, IsTheMedianRoundedToAKilometre) {
  const Eigen::Vector3d centre = kUtm + Eigen::Vector3d(321.0, -456.0, 812.0);
  const LocalOrigin o = ChooseLocalOrigin(Cloud(centre, 200.0, 5000));
  EXPECT_EQ(o.t_user_local, Eigen::Vector3d(500000.0, 5400000.0, 1000.0));
  // A trajectory's positions give the same rule.
  Trajectory t(3);
  for (size_t i = 0; i < t.size(); ++i) t[i].p_world_imu = centre + Eigen::Vector3d(i, 0, 0);
  EXPECT_EQ(ChooseLocalOrigin(t).t_user_local, o.t_user_local);
}

TEST(LocalOrigin, StrayAndNonFinitePointsDoNotMoveIt) {
  std::vector<Eigen::Vector3d> p = Cloud(kUtm, 50.0, 2000);
  p.push_back(Eigen::Vector3d::Zero());                                // a survey's blunder at 0
  p.push_back(kUtm + Eigen::Vector3d(250000.0, 0.0, 0.0));             // one 250 km away
  p.push_back(Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0));
  p.push_back(Eigen::Vector3d(0.0, std::numeric_limits<double>::infinity(), 0.0));
  EXPECT_EQ(ChooseLocalOrigin(p).t_user_local, kUtm);
}

TEST(LocalOrigin, LargeCloudsAreSubsampledToTheSameOrigin) {
  const std::vector<Eigen::Vector3d> p = Cloud(kUtm + Eigen::Vector3d(0.0, 0.0, 300.0), 400.0, 300000);
  EXPECT_EQ(ChooseLocalOrigin(p).t_user_local, kUtm);
}

TEST(LocalOrigin, RoundTripKeepsTheCoordinates) {
  const LocalOrigin o{kUtm};
  std::vector<Eigen::Vector3d> p = Cloud(kUtm, 1000.0, 100);
  const std::vector<Eigen::Vector3d> original = p;
  o.ToLocal(&p);
  for (size_t i = 0; i < p.size(); ++i) {
    EXPECT_LT(p[i].cwiseAbs().maxCoeff(), 1000.0);
    EXPECT_EQ(o.ToUser(p[i]), original[i]);  // subtracting and adding 5.4e6 m back is exact here
  }
  o.ToUser(&p);
  EXPECT_EQ(p, original);
  Trajectory t(1);
  t[0].p_world_imu = kUtm + Eigen::Vector3d(0.001, 0.002, 0.003);
  t[0].q_world_imu = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  o.ToLocal(&t);
  EXPECT_NEAR((t[0].p_world_imu - Eigen::Vector3d(0.001, 0.002, 0.003)).norm(), 0.0, 1e-9);
  EXPECT_NEAR(t[0].q_world_imu.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()))),
              0.0, 1e-15);
  o.ToUser(&t);
  EXPECT_NEAR((t[0].p_world_imu - kUtm - Eigen::Vector3d(0.001, 0.002, 0.003)).norm(), 0.0, 1e-9);
}

TEST(LocalOrigin, Float32StepsAtSurveyCoordinates) {
  EXPECT_EQ(Float32Step(5400000.0), 0.5);     // a UTM northing
  EXPECT_EQ(Float32Step(-500000.0), 0.03125);  // a UTM easting
  EXPECT_LT(Float32Step(kFloat32MillimetreReach_m - 1.0), 1e-3);
  EXPECT_GE(Float32Step(kFloat32MillimetreReach_m), 0.9e-3);
}

}  // namespace
}  // namespace rvlio

// Paper Section 3.2: the observability conditions behind Proposition 1.
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "rv_test_util.h"
#include "rvlio/rv/criterion.h"
#include "rvlio/rv/rv.h"

namespace rvlio {
namespace {

using test::RandomUnit;

int Rank(const Eigen::MatrixXd& M) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(M);
  const Eigen::VectorXd s = svd.singularValues();
  int r = 0;
  for (int i = 0; i < s.size(); ++i) r += s(i) > 1e-9 * std::max(1.0, s(0));
  return r;
}

Eigen::Matrix3d Hat(const Eigen::Vector3d& a) {
  Eigen::Matrix3d h;
  h << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return h;
}

// Eq. (13): the position block has rows u_i^T.
Eigen::MatrixXd PositionBlock(const std::vector<Eigen::Vector3d>& normals) {
  Eigen::MatrixXd O(normals.size(), 3);
  for (size_t i = 0; i < normals.size(); ++i) O.row(i) = normals[i].transpose();
  return O;
}

// Eq. (6): the rotation block has rows u_i^T (-R p_i)^.
Eigen::MatrixXd RotationBlock(const std::vector<Eigen::Vector3d>& normals,
                              const std::vector<Eigen::Vector3d>& points_imu,
                              const Eigen::Matrix3d& R) {
  Eigen::MatrixXd O(normals.size(), 3);
  for (size_t i = 0; i < normals.size(); ++i) {
    O.row(i) = normals[i].transpose() * Hat(-(R * points_imu[i]));
  }
  return O;
}

ConstraintList FromNormals(const std::vector<Eigen::Vector3d>& normals) {
  ConstraintList list(normals.size());
  for (size_t i = 0; i < normals.size(); ++i) list[i].normal_world = normals[i];
  return list;
}

TEST(ObservabilityTest, CoplanarNormalsFailCondition2AndActivateCriterion) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Vector3d axis = RandomUnit(rng);
    std::vector<Eigen::Vector3d> normals;
    for (int i = 0; i < 200; ++i) {
      Eigen::Vector3d u = RandomUnit(rng);
      normals.push_back((u - u.dot(axis) * axis).normalized());  // Figure 2(a)
    }
    EXPECT_EQ(Rank(PositionBlock(normals)), 2);
    RvOptions options;
    RvWorkspace ws;
    const CriterionResult c = EvaluateCriterion(options, FromNormals(normals), &ws);
    EXPECT_TRUE(c.active);
    EXPECT_NEAR(std::abs(c.fit.n_alpha.dot(axis)), 1.0, 1e-9);
    EXPECT_NEAR(c.fit.eigenvalues(0), 0.0, 1e-9);
    EXPECT_EQ(c.num_within_eps0, 200);
    // The information matrix has the axis in its null space.
    EXPECT_NEAR(SmallestEigenvalue(PositionInformation(FromNormals(normals))), 0.0, 1e-9);
  }
}

TEST(ObservabilityTest, ThreeIndependentPlanesSatisfyCondition2AndDoNotActivate) {
  std::mt19937 rng(12);
  std::normal_distribution<double> noise(0.0, 0.02);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Matrix3d R = test::RandomPose(rng).R;
    std::vector<Eigen::Vector3d> normals;
    for (int i = 0; i < 300; ++i) {  // Figure 2(b): three non-coplanar plane normals
      const Eigen::Vector3d base = R.col(i % 3);
      normals.push_back((base + Eigen::Vector3d(noise(rng), noise(rng), noise(rng))).normalized());
    }
    EXPECT_EQ(Rank(PositionBlock(normals)), 3);
    RvOptions options;
    RvWorkspace ws;
    const CriterionResult c = EvaluateCriterion(options, FromNormals(normals), &ws);
    EXPECT_FALSE(c.active);
    EXPECT_LT(c.coplanar_fraction, 0.8);
    EXPECT_GT(SmallestEigenvalue(PositionInformation(FromNormals(normals))), 50.0);
  }
}

TEST(ObservabilityTest, ExactlyThreeIndependentNormalsGiveRank3) {
  std::mt19937 rng(13);
  for (int trial = 0; trial < 100; ++trial) {
    const std::vector<Eigen::Vector3d> n = {RandomUnit(rng), RandomUnit(rng), RandomUnit(rng)};
    ASSERT_GT(std::abs(n[0].cross(n[1]).dot(n[2])), 1e-3);
    EXPECT_EQ(Rank(PositionBlock(n)), 3);
  }
}

// Points on the plane u . x = c (c != 0, so no point is at the origin).
std::vector<Eigen::Vector3d> PointsOnPlane(std::mt19937& rng, const Eigen::Vector3d& u, double c,
                                           int count) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < count; ++i) {
    Eigen::Vector3d t = 10.0 * RandomUnit(rng);
    t -= t.dot(u) * u;
    pts.push_back(c * u + t);
  }
  return pts;
}

TEST(ObservabilityTest, Condition1TwoNonParallelPlanesTwoPointsEachGiveFullRotationRank) {
  std::mt19937 rng(14);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d u0 = RandomUnit(rng), u1 = RandomUnit(rng);
    ASSERT_LT(std::abs(u0.dot(u1)), 1.0 - 1e-3);  // non-parallel
    const Eigen::Matrix3d R = test::RandomPose(rng).R;
    // The points are expressed in the IMU frame: plane (R^T u) . p = c.
    std::vector<Eigen::Vector3d> normals, points;
    for (const auto& [u, c] : {std::pair{u0, 3.0}, std::pair{u1, -4.0}}) {
      for (const Eigen::Vector3d& p : PointsOnPlane(rng, R.transpose() * u, c, 2)) {
        normals.push_back(u);
        points.push_back(p);
      }
    }
    EXPECT_EQ(Rank(RotationBlock(normals, points, R)), 3) << "trial " << trial;
  }
}

TEST(ObservabilityTest, OnePlaneOnlyGivesRotationRank2WithTheNormalInTheNullSpace) {
  std::mt19937 rng(15);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d u = RandomUnit(rng);
    const Eigen::Matrix3d R = test::RandomPose(rng).R;
    const std::vector<Eigen::Vector3d> points = PointsOnPlane(rng, R.transpose() * u, 2.5, 20);
    const std::vector<Eigen::Vector3d> normals(points.size(), u);
    const Eigen::MatrixXd O = RotationBlock(normals, points, R);
    EXPECT_EQ(Rank(O), 2);            // Eq. (10)
    EXPECT_LT((O * u).norm(), 1e-9);  // Eq. (12): u_alpha spans the null space
  }
}

}  // namespace
}  // namespace rvlio

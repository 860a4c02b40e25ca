// Alg. 1: plane fit, coplanarity distance, SCVs and activation.
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "rv_test_util.h"
#include "rvlio/rv/criterion.h"

namespace rvlio {
namespace {

using test::RandomUnit;

TEST(CriterionTest, FitPlaneIsTheMinimizerOfTheSumOfSquaredDistances) {
  std::mt19937 rng(21);
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    std::vector<Eigen::Vector3d> u;
    for (int i = 0; i < 30; ++i) {
      u.push_back(RandomUnit(rng));
      S += u.back() * u.back().transpose();
    }
    const PlaneFit fit = FitPlane(S);
    EXPECT_NEAR(fit.n_alpha.norm(), 1.0, 1e-12);
    EXPECT_LE(fit.eigenvalues(0), fit.eigenvalues(1));
    EXPECT_LE(fit.eigenvalues(1), fit.eigenvalues(2));
    EXPECT_LT((S * fit.n_alpha - fit.eigenvalues(0) * fit.n_alpha).norm(), 1e-9);
    // It is the last right singular vector of A = [u_i^T] (Eq. 14).
    Eigen::MatrixXd A(u.size(), 3);
    for (size_t i = 0; i < u.size(); ++i) A.row(i) = u[i].transpose();
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinV);
    EXPECT_NEAR(std::abs(svd.matrixV().col(2).dot(fit.n_alpha)), 1.0, 1e-8);
    // No other direction has a smaller sum of d_i^2.
    double best = 0.0;
    for (const auto& v : u) best += std::pow(v.dot(fit.n_alpha), 2);
    for (int k = 0; k < 50; ++k) {
      const Eigen::Vector3d m = RandomUnit(rng);
      double sum = 0.0;
      for (const auto& v : u) sum += std::pow(v.dot(m), 2);
      EXPECT_GE(sum, best - 1e-9);
    }
    // Deterministic sign: the largest component is positive.
    int largest = 0;
    fit.n_alpha.cwiseAbs().maxCoeff(&largest);
    EXPECT_GT(fit.n_alpha(largest), 0.0);
  }
}

TEST(CriterionTest, FitPlaneOfZeroScatterIsFinite) {
  const PlaneFit fit = FitPlane(Eigen::Matrix3d::Zero());
  EXPECT_TRUE(fit.n_alpha.allFinite());
  EXPECT_NEAR(fit.n_alpha.norm(), 1.0, 1e-12);
}

TEST(CriterionTest, DistanceIsAbsoluteAndSignInvariant) {
  std::mt19937 rng(22);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Vector3d u = RandomUnit(rng), n = RandomUnit(rng);
    EXPECT_DOUBLE_EQ(CoplanarityDistance(u, n), std::abs(u.dot(n)));
    EXPECT_DOUBLE_EQ(CoplanarityDistance(-u, n), CoplanarityDistance(u, n));
    EXPECT_GE(CoplanarityDistance(u, n), 0.0);
  }
}

TEST(CriterionTest, ScvsAndFractionMatchTheDefinition) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 100; ++trial) {
    test::TunnelSpec spec;
    spec.num_coplanar = 300;
    spec.num_scv = trial % 40;
    const test::TunnelSet set = test::MakeTunnelSet(rng, spec);
    RvOptions options;
    RvWorkspace ws;
    const CriterionResult c = EvaluateCriterion(options, set.list, &ws);
    int within = 0;
    for (int i = 0; i < ws.size(); ++i) {
      const double d = std::abs(set.list[i].normal_world.normalized().dot(c.fit.n_alpha));
      EXPECT_NEAR(ws.d[i], d, 1e-12);
      EXPECT_EQ(ws.cls[i] == VectorClass::kScv, d > options.eps0);
      within += d <= options.eps0;
    }
    EXPECT_EQ(c.num_within_eps0, within);
    EXPECT_EQ(c.num_usable, 300 + spec.num_scv);
    EXPECT_DOUBLE_EQ(c.coplanar_fraction, within / static_cast<double>(c.num_usable));
    EXPECT_EQ(c.active, c.coplanar_fraction >= options.activation_ratio);
  }
}

TEST(CriterionTest, ActivationFollowsRatioAndMinimumCount) {
  std::mt19937 rng(24);
  test::TunnelSpec spec;
  spec.num_coplanar = 90;
  spec.num_scv = 10;  // exactly 90 % coplanar
  const test::TunnelSet set = test::MakeTunnelSet(rng, spec);
  RvOptions options;
  RvWorkspace ws;
  options.activation_ratio = 0.9;
  EXPECT_TRUE(EvaluateCriterion(options, set.list, &ws).active);
  options.activation_ratio = 0.91;
  EXPECT_FALSE(EvaluateCriterion(options, set.list, &ws).active);
  options.activation_ratio = 0.9;
  options.min_constraints = 100;
  EXPECT_TRUE(EvaluateCriterion(options, set.list, &ws).active);
  options.min_constraints = 101;
  EXPECT_FALSE(EvaluateCriterion(options, set.list, &ws).active);
}

TEST(CriterionTest, UnusableNormalsAreIgnored) {
  std::mt19937 rng(25);
  test::TunnelSpec spec;
  spec.num_coplanar = 100;
  spec.num_scv = 0;
  test::TunnelSet set = test::MakeTunnelSet(rng, spec);
  RvOptions options;
  RvWorkspace ws;
  const CriterionResult clean = EvaluateCriterion(options, set.list, &ws);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  set.list[3].normal_world = Eigen::Vector3d(nan, 0, 1);
  set.list[7].normal_world = Eigen::Vector3d::Zero();
  set.list[9].normal_world = Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0, 0);
  ConstraintList reduced;
  for (size_t i = 0; i < set.list.size(); ++i) {
    if (i != 3 && i != 7 && i != 9) reduced.push_back(set.list[i]);
  }
  const CriterionResult dirty = EvaluateCriterion(options, set.list, &ws);
  EXPECT_EQ(ws.cls[3], VectorClass::kUnusable);
  EXPECT_EQ(ws.cls[7], VectorClass::kUnusable);
  EXPECT_EQ(ws.cls[9], VectorClass::kUnusable);
  EXPECT_EQ(dirty.num_usable, 97);
  RvWorkspace ws2;
  const CriterionResult ref = EvaluateCriterion(options, reduced, &ws2);
  EXPECT_LT((dirty.fit.n_alpha - ref.fit.n_alpha).norm(), 1e-12);
  EXPECT_EQ(dirty.num_within_eps0, ref.num_within_eps0);
  EXPECT_TRUE(dirty.fit.n_alpha.allFinite());
  EXPECT_TRUE(clean.active);
}

TEST(CriterionTest, UnnormalizedNormalsAreNormalizedFirst) {
  std::mt19937 rng(26);
  test::TunnelSpec spec;
  spec.num_coplanar = 200;
  spec.num_scv = 10;
  test::TunnelSet set = test::MakeTunnelSet(rng, spec);
  RvOptions options;
  RvWorkspace ws;
  const CriterionResult a = EvaluateCriterion(options, set.list, &ws);
  std::uniform_real_distribution<double> scale(0.1, 10.0);
  for (Constraint& c : set.list) c.normal_world *= scale(rng);  // Alg. 1 step 1
  const CriterionResult b = EvaluateCriterion(options, set.list, &ws);
  EXPECT_LT((a.fit.n_alpha - b.fit.n_alpha).norm(), 1e-9);
  EXPECT_EQ(a.num_within_eps0, b.num_within_eps0);
}

}  // namespace
}  // namespace rvlio

// The whole RV pass: switches, report, degenerate inputs and properties.
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "rv_test_util.h"
#include "rvlio/rv/reinforce.h"
#include "rvlio/rv/rv.h"

namespace rvlio {
namespace {

using test::RandomUnit;
using test::SameList;

bool AllFinite(const ConstraintList& list) {
  for (const Constraint& c : list) {
    if (!c.p_lidar.allFinite() || !c.normal_world.allFinite() || !c.q_world.allFinite() ||
        !std::isfinite(c.residual) || !std::isfinite(c.weight)) {
      return false;
    }
  }
  return true;
}

bool ReportFinite(const RvReport& r) {
  return r.n_alpha.allFinite() && std::isfinite(r.K) && r.s_eigenvalues.allFinite() &&
         std::isfinite(r.localizability) && std::isfinite(r.coplanar_fraction);
}

test::TunnelSet DefaultTunnel(std::mt19937& rng) {
  test::TunnelSpec spec;
  spec.num_coplanar = 1000;
  spec.num_scv = 50;
  spec.axial_noise = 0.03;
  return test::MakeTunnelSet(rng, spec);
}

TEST(ApplyRvTest, DisabledLeavesTheListUntouched) {
  std::mt19937 rng(51);
  const test::TunnelSet set = DefaultTunnel(rng);
  RvOptions options;
  options.enabled = false;
  ConstraintList list = set.list;
  const RvReport report = ApplyRv(options, set.T_world_lidar, &list);
  EXPECT_TRUE(SameList(list, set.list));
  EXPECT_FALSE(report.active);
  EXPECT_EQ(report.num_constraints, 1050);
  EXPECT_NEAR(report.localizability, SmallestEigenvalue(PositionInformation(set.list)), 1e-12);
}

TEST(ApplyRvTest, BothModulesOffLeaveTheListUntouchedButReport) {
  std::mt19937 rng(52);
  const test::TunnelSet set = DefaultTunnel(rng);
  RvOptions options;
  options.reinforce = false;
  options.repair = false;
  ConstraintList list = set.list;
  const RvReport report = ApplyRv(options, set.T_world_lidar, &list);
  EXPECT_TRUE(SameList(list, set.list));
  EXPECT_TRUE(report.active);
  EXPECT_EQ(report.num_scv, 50);
  EXPECT_EQ(report.num_reinforced, 0);
  EXPECT_EQ(report.num_repaired, 0);
}

TEST(ApplyRvTest, InactiveScanIsUntouched) {
  std::mt19937 rng(53);
  // Three independent plane families: Condition 2 holds, no activation.
  ConstraintList list;
  const Pose3 T = test::RandomPose(rng);
  for (int i = 0; i < 600; ++i) {
    list.push_back(test::MakeConstraint(rng, Eigen::Matrix3d::Identity().col(i % 3), T));
  }
  const ConstraintList original = list;
  const RvReport report = ApplyRv(RvOptions(), T, &list);
  EXPECT_FALSE(report.active);
  EXPECT_TRUE(SameList(list, original));
  EXPECT_EQ(report.K, 0.0);
  EXPECT_EQ(report.iterations, 0);
}

TEST(ApplyRvTest, EachModuleEditsOnlyItsOwnFields) {
  std::mt19937 rng(54);
  for (int trial = 0; trial < 50; ++trial) {
    const test::TunnelSet set = DefaultTunnel(rng);
    RvOptions reinforce_only;
    reinforce_only.repair = false;
    RvOptions repair_only;
    repair_only.reinforce = false;
    ConstraintList a = set.list, b = set.list;
    const RvReport ra = ApplyRv(reinforce_only, set.T_world_lidar, &a);
    const RvReport rb = ApplyRv(repair_only, set.T_world_lidar, &b);
    // The refit (plane and SCV set) is the same whichever module is on.
    EXPECT_EQ(ra.n_alpha, rb.n_alpha);
    EXPECT_EQ(ra.num_scv, rb.num_scv);
    EXPECT_EQ(ra.iterations, rb.iterations);
    EXPECT_GT(ra.num_reinforced, 0);
    EXPECT_GT(rb.num_repaired, 0);
    for (size_t i = 0; i < set.list.size(); ++i) {
      EXPECT_EQ(a[i].normal_world, set.list[i].normal_world);
      EXPECT_EQ(a[i].residual, set.list[i].residual);
      EXPECT_NE(a[i].role, RvRole::kRepaired);
      EXPECT_EQ(b[i].weight, set.list[i].weight);
      EXPECT_NE(b[i].role, RvRole::kScv);
    }
  }
}

TEST(ApplyRvTest, ReportIsConsistent) {
  std::mt19937 rng(55);
  for (int trial = 0; trial < 100; ++trial) {
    const test::TunnelSet set = DefaultTunnel(rng);
    ConstraintList list = set.list;
    RvOptions options;
    const RvReport r = ApplyRv(options, set.T_world_lidar, &list);
    ASSERT_TRUE(r.active);
    EXPECT_EQ(r.num_constraints, 1050);
    EXPECT_EQ(r.num_usable, 1050);
    EXPECT_EQ(r.num_scv + r.num_coplanar, r.num_usable);
    EXPECT_EQ(r.num_scv, 50);
    EXPECT_NEAR(r.n_alpha.norm(), 1.0, 1e-12);
    EXPECT_GT(std::abs(r.n_alpha.dot(set.axis)), std::cos(0.05));
    EXPECT_LE(r.s_eigenvalues(0), r.s_eigenvalues(1));
    EXPECT_LE(r.s_eigenvalues(1), r.s_eigenvalues(2));
    EXPECT_NEAR(r.s_eigenvalues.sum(), 1050.0, 1e-8);  // trace of sum u u^T, unit u
    EXPECT_DOUBLE_EQ(r.K, std::max(options.min_K, std::min(1.0, options.k0 * 50.0 / 1000.0)));
    int scv = 0, repaired = 0, fitting_scv = 0;
    for (const Constraint& c : list) {
      scv += c.role == RvRole::kScv;
      repaired += c.role == RvRole::kRepaired;
      fitting_scv += c.role == RvRole::kScv && std::abs(c.residual) <= options.reinforce_max_residual;
    }
    EXPECT_EQ(scv, r.num_scv);
    EXPECT_EQ(fitting_scv, r.num_reinforced);  // the default gate leaves the others alone
    EXPECT_EQ(repaired, r.num_repaired);
    EXPECT_NEAR(r.localizability, SmallestEigenvalue(PositionInformation(list)), 1e-9);
  }
}

TEST(ApplyRvTest, WorkspaceReuseGivesTheSameResult) {
  std::mt19937 rng(56);
  RvWorkspace ws;
  for (int trial = 0; trial < 30; ++trial) {
    test::TunnelSpec spec;
    spec.num_coplanar = 100 + 97 * trial % 1500;
    spec.num_scv = trial % 9;
    const test::TunnelSet set = test::MakeTunnelSet(rng, spec);
    ConstraintList a = set.list, b = set.list;
    const RvReport ra = ApplyRv(RvOptions(), set.T_world_lidar, &a, &ws);
    const RvReport rb = ApplyRv(RvOptions(), set.T_world_lidar, &b);
    EXPECT_TRUE(SameList(a, b));
    EXPECT_EQ(ra.n_alpha, rb.n_alpha);
    EXPECT_EQ(ra.num_repaired, rb.num_repaired);
  }
}

TEST(ApplyRvTest, PositionInformationIsTheWeightedScatter) {
  std::mt19937 rng(57);
  const test::TunnelSet set = DefaultTunnel(rng);
  Eigen::Matrix3d expected = Eigen::Matrix3d::Zero();
  for (const Constraint& c : set.list)
    expected += c.weight * c.normal_world * c.normal_world.transpose();
  EXPECT_LT((PositionInformation(set.list) - expected).norm(), 1e-9);
  EXPECT_LT((PositionInformation(set.list, 0.05) - expected / 0.0025).norm(), 1e-6);
  EXPECT_EQ(PositionInformation(ConstraintList()), Eigen::Matrix3d::Zero());
}

TEST(ApplyRvDegenerateTest, TinyListsAreNeverActive) {
  std::mt19937 rng(58);
  for (int n = 0; n <= 2; ++n) {
    ConstraintList list;
    for (int i = 0; i < n; ++i) list.push_back(test::MakeConstraint(rng, RandomUnit(rng), Pose3()));
    const ConstraintList original = list;
    RvOptions options;
    options.min_constraints = 3;
    options.activation_ratio = 0.0;
    const RvReport r = ApplyRv(options, Pose3(), &list);
    EXPECT_FALSE(r.active);
    EXPECT_TRUE(SameList(list, original));
    EXPECT_TRUE(ReportFinite(r));
    EXPECT_EQ(r.num_constraints, n);
  }
}

TEST(ApplyRvDegenerateTest, IdenticalNormalsStayFinite) {
  std::mt19937 rng(59);
  ConstraintList list;
  const Eigen::Vector3d u = RandomUnit(rng);
  for (int i = 0; i < 50; ++i) list.push_back(test::MakeConstraint(rng, u, Pose3()));
  RvOptions options;
  options.eps1 = options.eps0;
  const RvReport r = ApplyRv(options, Pose3(), &list);
  EXPECT_TRUE(r.active);  // all vectors lie in every plane containing u
  EXPECT_EQ(r.num_scv, 0);
  EXPECT_NEAR(r.n_alpha.dot(u), 0.0, 1e-9);
  EXPECT_EQ(r.num_repaired, 50);
  EXPECT_TRUE(AllFinite(list));
  EXPECT_TRUE(ReportFinite(r));
  for (const Constraint& c : list) EXPECT_LT((c.normal_world - u).norm(), 1e-9);
}

TEST(ApplyRvDegenerateTest, AllVectorsSpecialLeavesWeightsFinite) {
  std::mt19937 rng(60);
  // Two normals only, far from every common plane's tolerance.
  ConstraintList list;
  for (int i = 0; i < 40; ++i) {
    list.push_back(test::MakeConstraint(rng, Eigen::Matrix3d::Identity().col(i % 3), Pose3()));
  }
  RvOptions options;
  options.activation_ratio = 0.0;
  options.eps0 = 0.0;
  options.eps1 = 0.0;
  options.clamp = false;
  const RvReport r = ApplyRv(options, Pose3(), &list);
  EXPECT_TRUE(r.active);
  EXPECT_TRUE(AllFinite(list));
  EXPECT_TRUE(ReportFinite(r));
  EXPECT_EQ(r.num_scv + r.num_coplanar, 40);
}

TEST(ApplyRvDegenerateTest, NonFiniteNormalsAreLeftAloneAndDoNotSpread) {
  std::mt19937 rng(61);
  test::TunnelSet set = DefaultTunnel(rng);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  set.list[0].normal_world = Eigen::Vector3d(nan, nan, nan);
  set.list[1].normal_world = Eigen::Vector3d::Zero();
  ConstraintList list = set.list;
  const RvReport r = ApplyRv(RvOptions(), set.T_world_lidar, &list);
  EXPECT_TRUE(r.active);
  EXPECT_EQ(r.num_usable, 1048);
  EXPECT_TRUE(ReportFinite(r));
  EXPECT_EQ(list[1].normal_world, Eigen::Vector3d::Zero());
  EXPECT_EQ(list[0].role, RvRole::kPlain);
  EXPECT_EQ(list[1].role, RvRole::kPlain);
  for (size_t i = 1; i < list.size(); ++i) EXPECT_TRUE(list[i].normal_world.allFinite());
}

// Property: over random lists and random valid options, ApplyRv never produces
// a non-finite value and never changes the number of constraints.
TEST(ApplyRvPropertyTest, FiniteOutputAndSizePreserved) {
  std::mt19937 rng(62);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> size(0, 400), kind(0, 3);
  int active = 0;
  for (int trial = 0; trial < 400; ++trial) {
    ConstraintList list;
    Pose3 T = test::RandomPose(rng);
    switch (kind(rng)) {
      case 0: {  // random directions
        const int n = size(rng);
        for (int i = 0; i < n; ++i) list.push_back(test::MakeConstraint(rng, RandomUnit(rng), T));
        break;
      }
      case 1: {  // tunnel
        test::TunnelSpec spec;
        spec.num_coplanar = size(rng);
        spec.num_scv = size(rng) / 10;
        spec.axial_noise = 0.1 * unit(rng);
        test::TunnelSet set = test::MakeTunnelSet(rng, spec);
        list = set.list;
        T = set.T_world_lidar;
        break;
      }
      case 2: {  // few distinct directions, repeated
        const int n = size(rng);
        const Eigen::Vector3d a = RandomUnit(rng), b = RandomUnit(rng);
        for (int i = 0; i < n; ++i) list.push_back(test::MakeConstraint(rng, i % 3 ? a : b, T));
        break;
      }
      default: {  // exactly coplanar, random plane
        const int n = size(rng);
        const Eigen::Vector3d axis = RandomUnit(rng);
        for (int i = 0; i < n; ++i) {
          Eigen::Vector3d u = RandomUnit(rng);
          u -= u.dot(axis) * axis;
          if (u.norm() < 1e-3) u = axis.unitOrthogonal();
          list.push_back(test::MakeConstraint(rng, u.normalized(), T));
        }
      }
    }
    RvOptions options;
    options.reinforce = unit(rng) < 0.8;
    options.repair = unit(rng) < 0.8;
    options.eps0 = unit(rng);
    options.eps1 = options.eps0 * unit(rng);
    options.k0 = std::pow(10.0, -3.0 + 6.0 * unit(rng));
    options.activation_ratio = unit(rng);
    options.max_iterations = 1 + static_cast<int>(10 * unit(rng));
    options.clamp = unit(rng) < 0.5;
    options.min_constraints = 3 + static_cast<int>(30 * unit(rng));
    ASSERT_TRUE(options.Validate().ok());
    const size_t n_before = list.size();
    const RvReport r = ApplyRv(options, T, &list);
    ASSERT_EQ(list.size(), n_before);
    ASSERT_TRUE(AllFinite(list)) << "trial " << trial;
    ASSERT_TRUE(ReportFinite(r)) << "trial " << trial;
    EXPECT_EQ(r.num_constraints, static_cast<int>(n_before));
    EXPECT_LE(r.num_scv + r.num_coplanar, r.num_usable);
    EXPECT_LE(r.num_repaired + r.num_reinforced, static_cast<int>(n_before));
    for (const Constraint& c : list) {
      EXPECT_GT(c.weight, 0.0);
      EXPECT_NEAR(c.normal_world.norm(), 1.0, 1e-9);
    }
    active += r.active;
  }
  EXPECT_GT(active, 100);  // the property covered active passes, not only no-ops
}

}  // namespace
}  // namespace rvlio

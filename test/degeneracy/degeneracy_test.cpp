// The degeneracy methods on constructed constraint sets with a known answer:
// a corridor (walls and floor/ceiling: one weak translation, along it), a
// pipe (one weak translation, the axis; and the rotation about it), a plane
// (two weak translations in the plane, and the rotation about its normal)
// and a closed room (none). Sensor at the origin, world = LiDAR = IMU frame.
#include <algorithm>
#include <cmath>
#include <string>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/degeneracy/degeneracy.h"
#include "degeneracy_scenes.h"

namespace rvlio {
namespace {

using test::AddPoint;
using test::Corridor;
using test::Pipe;
using test::Plane;
using test::Room;
using test::Scene;

// sum_i h_i^T h_i of the pose columns (sigma = 1, unit weights).
PoseMatrix6d PoseInformation(const ConstraintList& constraints) {
  PoseMatrix6d H = PoseMatrix6d::Zero();
  Eigen::Matrix<double, 1, 6> h;
  for (const Constraint& c : constraints) {
    PointToPlaneResidual(c, Pose3(), Pose3(), &h);
    H += h.transpose() * h;
  }
  return H;
}

DegeneracyTreatment Analyze(DegeneracyMethod method, const Scene& s) {
  DegeneracyOptions o;
  o.method = method;
  return AnalyzeDegeneracy(o, PoseInformation(s.constraints), s.constraints, Pose3(), Pose3());
}

// Angle (deg) between d and the subspace spanned by the orthonormal `basis`.
double AngleToSpanDeg(const Eigen::Vector3d& d, const std::vector<Eigen::Vector3d>& basis) {
  Eigen::Vector3d in = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& b : basis) in += b * b.dot(d);
  return std::acos(std::min(1.0, in.norm() / d.norm())) * 180.0 / M_PI;
}

// The increment of each method against method none on A = H + a small
// isotropic prior plus three further states (velocity-like, uncoupled).
Eigen::VectorXd Increment(DegeneracyMethod method, const DegeneracyTreatment& t,
                          const PoseMatrix6d& H, const Eigen::VectorXd& b) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(9, 9) * 1e-2;
  A.topLeftCorner<6, 6>() += H;
  Eigen::VectorXd dx = -A.ldlt().solve(b);
  switch (method) {
    case DegeneracyMethod::kRemap:
      ProjectOutHeld(t, dx.head<6>());
      break;
    case DegeneracyMethod::kLocalizability:
      dx = SolveHoldingDirections(t, A, b);
      break;
    case DegeneracyMethod::kRegularized:
      A.topLeftCorner<6, 6>() += t.damping;
      dx = -A.ldlt().solve(b);
      break;
    default:
      break;
  }
  return dx;
}

class MethodTest : public ::testing::TestWithParam<DegeneracyMethod> {};

void CheckScene(DegeneracyMethod method, const Scene& s, const char* name) {
  SCOPED_TRACE(name);
  const DegeneracyTreatment t = Analyze(method, s);
  const DegeneracyReport& r = t.report;
  EXPECT_EQ(r.method, method);
  const int expected = static_cast<int>(s.weak_translations.size());
  EXPECT_EQ(r.degenerate, !s.weak_pose_indices.empty());
  ASSERT_EQ(r.num_weak, expected);
  for (int i = 0; i < r.num_weak; ++i) {
    EXPECT_NEAR(r.weak_dirs_world[i].norm(), 1.0, 1e-9);
    EXPECT_LT(AngleToSpanDeg(r.weak_dirs_world[i], s.weak_translations), 1.0);
  }
  if (method == DegeneracyMethod::kRegularized) {
    EXPECT_GE(r.num_damped, static_cast<int>(s.weak_pose_indices.size()));
  } else {
    EXPECT_EQ(r.num_held, static_cast<int>(s.weak_pose_indices.size()));
  }
  if (expected == 0) {
    EXPECT_LT(r.condition_number, 10.0);
  } else {
    EXPECT_GT(r.condition_number, 1e6);
  }

  // The update: unchanged along the well-constrained directions; no motion
  // (remap, localizability) or less (regularized) along the weak ones.
  const PoseMatrix6d H = PoseInformation(s.constraints);
  Eigen::VectorXd b(9);
  b << 3.0, -2.0, 1.5, 40.0, -25.0, 10.0, 0.3, -0.2, 0.1;
  const Eigen::VectorXd dx0 = Increment(DegeneracyMethod::kNone, t, H, b);
  const Eigen::VectorXd dx = Increment(method, t, H, b);
  for (int i = 0; i < 9; ++i) {
    const bool weak = std::find(s.weak_pose_indices.begin(), s.weak_pose_indices.end(), i) !=
                      s.weak_pose_indices.end();
    if (!weak) {
      EXPECT_NEAR(dx(i), dx0(i), 1e-9 * (1.0 + std::abs(dx0(i)))) << "entry " << i;
    } else if (method == DegeneracyMethod::kRegularized) {
      EXPECT_LT(std::abs(dx(i)), 0.01 * std::abs(dx0(i))) << "entry " << i;
    } else {
      EXPECT_NEAR(dx(i), 0.0, 1e-9) << "entry " << i;
    }
  }
}

TEST_P(MethodTest, CorridorPipePlaneRoom) {
  CheckScene(GetParam(), Corridor(), "corridor");
  CheckScene(GetParam(), Pipe(), "pipe");
  CheckScene(GetParam(), Plane(), "plane");
  CheckScene(GetParam(), Room(), "room");
}

INSTANTIATE_TEST_SUITE_P(Methods, MethodTest,
                         ::testing::Values(DegeneracyMethod::kRemap,
                                           DegeneracyMethod::kLocalizability,
                                           DegeneracyMethod::kRegularized),
                         [](const auto& info) { return std::string(EnumName(info.param)); });

TEST(Degeneracy, NoneAndRvReportOnly) {
  const Scene s = Corridor();
  const Eigen::Matrix3d H_tt = PoseInformation(s.constraints).block<3, 3>(3, 3);
  RvReport rv;
  rv.active = true;
  rv.n_alpha = Eigen::Vector3d::UnitX();
  const DegeneracyReport r = DegeneracyReportFromRv(DegeneracyMethod::kRv, rv, H_tt);
  EXPECT_TRUE(r.degenerate);
  ASSERT_EQ(r.num_weak, 1);
  EXPECT_EQ(r.weak_dirs_world[0], Eigen::Vector3d::UnitX());
  const DegeneracyReport none = DegeneracyReportFromRv(DegeneracyMethod::kNone, rv, H_tt);
  EXPECT_FALSE(none.degenerate);
  EXPECT_EQ(none.num_weak, 0);
  EXPECT_TRUE(std::isinf(none.condition_number));  // nothing along x
  const DegeneracyTreatment t = Analyze(DegeneracyMethod::kNone, s);
  EXPECT_EQ(t.num_held, 0);
  EXPECT_TRUE(t.damping.isZero());
}

TEST(Degeneracy, ConditionNumber) {
  EXPECT_DOUBLE_EQ(ConditionNumber(Eigen::Vector3d(1, 4, 8).asDiagonal().toDenseMatrix()), 8.0);
  EXPECT_TRUE(std::isnan(ConditionNumber(Eigen::Matrix3d::Zero())));
}

// A weakly (not exactly) constrained axis: remap's threshold decides.
TEST(Degeneracy, RemapThreshold) {
  Scene s = Corridor();
  for (int i = 0; i < 50; ++i) AddPoint({4.0, 0.0, 0.0}, {1, 0, 0}, &s.constraints);  // info 50 on x
  DegeneracyOptions o;
  o.method = DegeneracyMethod::kRemap;
  const PoseMatrix6d H = PoseInformation(s.constraints);
  EXPECT_TRUE(AnalyzeDegeneracy(o, H, s.constraints, Pose3(), Pose3()).report.degenerate);
  o.remap_min_eigenvalue = 40.0;
  EXPECT_FALSE(AnalyzeDegeneracy(o, H, s.constraints, Pose3(), Pose3()).report.degenerate);
}

// With coupling between the pose and the other states, the held solve is the
// constrained minimiser: zero along the held directions, and the gradient
// A dx + b orthogonal to every direction it may still move in.
TEST(Degeneracy, HoldingSolveIsTheConstrainedMinimiser) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd M(9, 9);
  for (int i = 0; i < 9; ++i)
    for (int j = 0; j < 9; ++j) M(i, j) = g(rng);
  const Eigen::MatrixXd A = M * M.transpose() + Eigen::MatrixXd::Identity(9, 9);
  Eigen::VectorXd b(9);
  for (int i = 0; i < 9; ++i) b(i) = g(rng);
  DegeneracyTreatment t;
  PoseVector6d v1 = PoseVector6d::Zero(), v2 = PoseVector6d::Zero();
  v1(3) = 1.0;                                      // the x translation
  v2 << 0.0, 0.0, 0.6, 0.0, 0.8, 0.0;               // a mixed direction
  t.held_pose.col(t.num_held++) = v1;
  t.held_pose.col(t.num_held++) = v2;
  const Eigen::VectorXd dx = SolveHoldingDirections(t, A, b);
  EXPECT_NEAR(v1.dot(dx.head<6>()), 0.0, 1e-12);
  EXPECT_NEAR(v2.dot(dx.head<6>()), 0.0, 1e-12);
  const Eigen::VectorXd gradient = A * dx + b;
  // Free directions: the 9-dim space orthogonal to [v1; 0] and [v2; 0].
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(9, 2);
  C.block<6, 1>(0, 0) = v1;
  C.block<6, 1>(0, 1) = v2;
  const Eigen::MatrixXd P = Eigen::MatrixXd::Identity(9, 9) - C * C.transpose();
  EXPECT_LT((P * gradient).norm(), 1e-9 * b.norm());
  // Nothing held: the plain solve.
  EXPECT_LT((SolveHoldingDirections(DegeneracyTreatment(), A, b) + A.ldlt().solve(b)).norm(), 1e-12);
}

TEST(Degeneracy, RvRunsOnlyAsTheSelectedMethod) {
  DegeneracyOptions d;
  RvOptions rv;
  EXPECT_TRUE(EffectiveRvOptions(rv, d).enabled);
  rv.enabled = false;
  EXPECT_FALSE(EffectiveRvOptions(rv, d).enabled);  // rv's own switch still works
  rv.enabled = true;
  for (DegeneracyMethod m : {DegeneracyMethod::kRemap, DegeneracyMethod::kLocalizability,
                             DegeneracyMethod::kRegularized, DegeneracyMethod::kNone}) {
    d.method = m;
    EXPECT_FALSE(EffectiveRvOptions(rv, d).enabled) << EnumName(m);
  }
}

// The smoother's and refine's form (a prior at an anchor): S^T S is the
// hold information along the held directions (remap, localizability), the
// IESKF's damping (regularized), nothing for rv and none; and the scan's
// pose information is the sum the IESKF builds.
TEST(Degeneracy, PriorOfTheLeastSquaresBackendsActsAlongTheTreatedDirectionsOnly) {
  const Scene s = Corridor();
  EXPECT_LT((ScanPoseInformation(s.constraints, Pose3(), Pose3()) - PoseInformation(s.constraints))
                .norm(),
            1e-9 * PoseInformation(s.constraints).norm());
  for (DegeneracyMethod m : {DegeneracyMethod::kRv, DegeneracyMethod::kNone, DegeneracyMethod::kRemap,
                             DegeneracyMethod::kLocalizability, DegeneracyMethod::kRegularized}) {
    SCOPED_TRACE(EnumName(m));
    DegeneracyOptions o;
    o.method = m;
    const DegeneracyTreatment t = Analyze(m, s);
    bool has_prior = true;
    const PoseMatrix6d S = DegeneracyPriorSqrtInformation(o, t, &has_prior);
    const PoseMatrix6d W = S.transpose() * S;
    if (m == DegeneracyMethod::kRv || m == DegeneracyMethod::kNone) {
      EXPECT_FALSE(has_prior);
      EXPECT_TRUE(W.isZero());
      continue;
    }
    ASSERT_TRUE(has_prior);
    if (m == DegeneracyMethod::kRegularized) {
      EXPECT_LT((W - t.damping).norm(), 1e-9 * t.damping.norm());
    } else {
      const Eigen::MatrixXd V = t.held_pose.leftCols(t.num_held);
      EXPECT_LT((W - o.hold_information * V * V.transpose()).norm(), 1e-6 * o.hold_information);
    }
    // Along the corridor's axis (pose index 3) and nowhere in the
    // well-constrained translations.
    EXPECT_GT(W(3, 3), 0.0);
    EXPECT_LT(std::abs(W(4, 4)) + std::abs(W(5, 5)), 1e-9 * W(3, 3));
  }
}

}  // namespace
}  // namespace rvlio

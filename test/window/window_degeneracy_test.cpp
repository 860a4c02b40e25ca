// The degeneracy methods in the sliding window (docs/degeneracy.md
// "Backends"), on noise-free constructed scenes with a known answer. Two
// states; the second starts at its true pose moved by a known offset (its
// "IMU prediction") and has no IMU factor, so only its scan and the
// method's prior decide it.
//   Corridor: walls y = +-3 and floor/ceiling z = +-3 along x, and a small
//   end wall x = 8 (20 points on a symmetric grid): the translation along x
//   is weak but not null. Without a treatment the solve recovers the truth;
//   remap and localizability hold x at the prediction, regularized damps it
//   to the condition floor (half way here), and none of them moves the
//   well-constrained directions.
//   Room: a closed box. No method finds a weak direction: the result equals
//   the untreated one.
//   Corridor with an IMU factor (constant velocity along x, exact samples):
//   remap in its default form (degeneracy.remap_window_form project) leaves
//   x to the IMU chain, which knows the truth; in the hold form it stays at
//   the prediction, as localizability.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/imu/noise.h"
#include "rvlio/imu/preintegration.h"
#include "rvlio/window/window.h"
#include "degeneracy/degeneracy_scenes.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

// The planes' points and normals of a constructed scene
// (test/degeneracy/degeneracy_scenes.h).
struct World {
  std::vector<Vector3d> q_world, n_world;
};

World FromScene(const test::Scene& scene) {
  World w;
  for (const Constraint& c : scene.constraints) {
    w.q_world.push_back(c.q_world);
    w.n_world.push_back(c.normal_world);
  }
  return w;
}

// The corridor and a small end wall x = 8 on a symmetric grid: weak but not
// null along x, and no coupling of x with the rotations.
World Corridor() {
  test::Scene scene = test::Corridor();
  for (double y : {-2.0, -1.0, 0.0, 1.0, 2.0})
    for (double z : {-1.5, -0.5, 0.5, 1.5}) test::AddPoint({8.0, y, z}, {-1, 0, 0}, &scene.constraints);
  return FromScene(scene);
}

World Room() { return FromScene(test::Room()); }

// The world's points in the LiDAR (= IMU) frame of a pose.
std::vector<Vector3d> Observe(const World& w, const Pose3& T_world_imu) {
  std::vector<Vector3d> p;
  for (const Vector3d& q : w.q_world) p.push_back(T_world_imu.Inverse() * q);
  return p;
}

// Exact association: point i lies on plane i, whatever the pose.
ScanAssociateFn Associate(const World& w) {
  return [&w](const std::vector<Vector3d>& p_lidar, const Pose3&, ConstraintList* out) {
    out->clear();
    for (size_t i = 0; i < p_lidar.size(); ++i) {
      Constraint c;
      c.p_lidar = p_lidar[i];
      c.normal_world = w.n_world[i];
      c.q_world = w.q_world[i];
      out->push_back(c);
    }
  };
}

struct Outcome {
  PoseBlock::Tangent error;  // second state: estimate [-] truth
  DegeneracyReport report;
};

const PoseBlock& TruePose1() {
  static const PoseBlock p(Eigen::Quaterniond::Identity(), Vector3d(0.5, 0.0, 0.0));
  return p;
}

// The prediction's offset from the truth: translation in every axis and a
// small yaw.
PoseBlock::Tangent PredictionOffset() {
  PoseBlock::Tangent d;
  d << 0.0, 0.0, 0.004, 0.05, 0.03, -0.02;
  return d;
}

constexpr TimeNs kDegenT0 = 1000000000, kDegenDt = 100000000;

// Exact samples of the motion from the origin to TruePose1 at constant
// velocity, level, no rotation.
ImuPreintegration ConstantVelocityImu(const WindowOptions& o) {
  std::vector<ImuSample> samples;
  for (TimeNs t = kDegenT0 - 5000000; t <= kDegenT0 + kDegenDt + 5000000; t += 5000000) {
    ImuSample s;
    s.t_ns = t;
    s.acc_imu = -test::Gravity();
    samples.push_back(s);
  }
  return ImuPreintegration::FromSamples(samples, kDegenT0, kDegenT0 + kDegenDt,
                                        ImuNoise::FromOptions(o.imu), Vector3d::Zero(),
                                        Vector3d::Zero());
}

Outcome Solve(const World& w, DegeneracyMethod method, bool with_imu = false,
              RemapWindowForm remap_form = RemapWindowForm::kProject) {
  WindowOptions o;
  o.rv.enabled = false;
  o.smoother.sliding_window_huber_delta = 10.0;  // unit weights: the scene's symmetry holds
  o.smoother.max_solver_iterations = 30;
  o.degeneracy.method = method;
  o.degeneracy.remap_window_form = remap_form;
  SlidingWindow window(o);
  const PoseBlock T0;
  SpeedBiasBlock sb;
  if (with_imu) sb.v_world_imu = TruePose1().p_world_imu / NsToSeconds(kDegenDt);
  std::optional<ImuPreintegration> imu;
  if (with_imu) imu = ConstantVelocityImu(o);
  window.Start(kDegenT0, T0, sb, Observe(w, T0.ToPose3()));
  window.Add(kDegenT0 + kDegenDt, Plus(TruePose1(), PredictionOffset()), sb, imu,
             Observe(w, TruePose1().ToPose3()));
  const WindowSolveReport report = window.Optimize(Associate(w));
  EXPECT_TRUE(report.ok);
  return {Minus(window.state(1).pose, TruePose1()), report.newest_degeneracy};
}

TEST(WindowDegeneracy, CorridorTreatsOnlyTheWeakAxis) {
  const World w = Corridor();
  const Outcome none = Solve(w, DegeneracyMethod::kNone);
  EXPECT_LT(none.error.norm(), 1e-6) << none.error.transpose();  // x is weak, not null
  const double x_offset = PredictionOffset()(3);
  for (DegeneracyMethod m :
       {DegeneracyMethod::kRemap, DegeneracyMethod::kLocalizability, DegeneracyMethod::kRegularized}) {
    SCOPED_TRACE(EnumName(m));
    const Outcome o = Solve(w, m);
    ASSERT_TRUE(o.report.degenerate);
    EXPECT_EQ(o.report.method, m);
    ASSERT_EQ(o.report.num_weak, 1);
    EXPECT_LT(std::acos(std::min(1.0, std::abs(o.report.weak_dirs_world[0].x()))) * 180.0 / M_PI,
              1.0);
    // The well-constrained directions: the untreated solution.
    EXPECT_LT((o.error.head<3>() - none.error.head<3>()).norm(), 1e-6) << o.error.transpose();
    EXPECT_LT((o.error.tail<2>() - none.error.tail<2>()).norm(), 1e-6) << o.error.transpose();
    if (m == DegeneracyMethod::kRegularized) {
      // x information 20 of the end wall, floor 400 / 10 = 40: the damping
      // (20) weighs the prediction as much as the scan.
      EXPECT_NEAR(o.error(3), 0.5 * x_offset, 0.05 * x_offset);
    } else {
      EXPECT_NEAR(o.error(3), x_offset, 1e-4);  // held at the prediction
    }
  }
}

TEST(WindowDegeneracy, RoomHasNoWeakDirectionAndIsLeftAlone) {
  const World w = Room();
  const Outcome none = Solve(w, DegeneracyMethod::kNone);
  EXPECT_LT(none.error.norm(), 1e-6);
  for (DegeneracyMethod m :
       {DegeneracyMethod::kRemap, DegeneracyMethod::kLocalizability, DegeneracyMethod::kRegularized}) {
    SCOPED_TRACE(EnumName(m));
    const Outcome o = Solve(w, m);
    EXPECT_FALSE(o.report.degenerate);
    EXPECT_EQ(o.report.num_weak, 0);
    EXPECT_EQ(o.error, none.error);  // the same problem: the same bits
  }
}

TEST(WindowDegeneracy, RemapLeavesTheWeakAxisToTheImuChainOrHoldsItAtThePrediction) {
  const World w = Corridor();
  const double x_offset = PredictionOffset()(3);
  const Outcome project = Solve(w, DegeneracyMethod::kRemap, true, RemapWindowForm::kProject);
  ASSERT_TRUE(project.report.degenerate);
  EXPECT_LT(std::abs(project.error(3)), 0.02 * x_offset) << project.error.transpose();
  const Outcome hold = Solve(w, DegeneracyMethod::kRemap, true, RemapWindowForm::kHold);
  ASSERT_TRUE(hold.report.degenerate);
  EXPECT_NEAR(hold.error(3), x_offset, 0.02 * x_offset) << hold.error.transpose();
  // The other directions: the scan and the IMU agree with the truth.
  for (const Outcome* o : {&project, &hold}) {
    EXPECT_LT(o->error.head<3>().norm(), 1e-4) << o->error.transpose();
    EXPECT_LT(o->error.tail<2>().norm(), 1e-4) << o->error.transpose();
  }
}

}  // namespace
}  // namespace rvlio

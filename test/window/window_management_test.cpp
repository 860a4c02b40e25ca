// SlidingWindow (window/window.h) on a synthetic world with exact
// association: a box room, the closed-form motion of smoother_test_util.h,
// noisy scans and noisy IMU samples.
//   - marginalization keeps the solution consistent: the newest state of a
//     small window that marginalizes equals a batch solve over all states;
//   - IMU gaps and zero intervals: states without an IMU factor stay solvable;
//   - a solve that fails or diverges restores the last good window state;
//   - sequences shorter than the window; bias re-integration; RV plumbing.
#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/imu/integrator.h"
#include "rvlio/lidar/extrinsics.h"
#include "rvlio/math/so3.h"
#include "rvlio/window/window.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

constexpr TimeNs kT0 = 2000000000;    // s = 2
constexpr TimeNs kScanNs = 100000000;  // 10 Hz
const Vector3d kHalf(8.0, 6.0, 3.0);   // room half extents, m

// Exact association in the box room: every point matches the wall nearest to
// it at the given pose.
void BoxAssociate(const Pose3& T_imu_lidar, const std::vector<Vector3d>& p_lidar,
                  const Pose3& T_world_imu, ConstraintList* out) {
  out->clear();
  const Pose3 T_world_lidar = T_world_imu * T_imu_lidar;
  for (const Vector3d& p : p_lidar) {
    const Vector3d w = T_world_lidar * p;
    int axis = 0;
    for (int i = 1; i < 3; ++i)
      if (kHalf(i) - std::abs(w(i)) < kHalf(axis) - std::abs(w(axis))) axis = i;
    const double side = w(axis) >= 0 ? 1.0 : -1.0;
    Constraint c;
    c.p_lidar = p;
    c.normal_world = -side * Vector3d::Unit(axis);
    c.q_world = w;
    c.q_world(axis) = side * kHalf(axis);
    c.residual = c.normal_world.dot(w - c.q_world);
    out->push_back(c);
  }
}

struct Sequence {
  std::vector<ImuSample> imu;                    // noisy, biased
  std::vector<std::vector<Vector3d>> scans;      // noisy points, LiDAR frame, per state
  Vector3d bg, ba;                               // true biases
};

Sequence MakeSequence(int states, uint32_t seed, const Pose3& T_imu_lidar, double point_noise,
                      const Vector3d& bg, const Vector3d& ba) {
  std::mt19937 rng(seed);
  Sequence s;
  s.bg = bg;
  s.ba = ba;
  s.imu = test::SimulateImu(kT0, kT0 + states * kScanNs, 2500000, bg, ba);  // 400 Hz
  for (ImuSample& m : s.imu) {  // white noise well above the integration error
    m.gyro_imu += test::RandomVector(rng, 2e-3);
    m.acc_imu += test::RandomVector(rng, 2e-2);
  }
  for (int k = 0; k < states; ++k) {
    const ConstraintList exact =
        test::BoxRoomScan(rng, test::TruePose(kT0 + k * kScanNs).ToPose3(), T_imu_lidar, 250,
                          kHalf);
    std::vector<Vector3d> points;
    for (const Constraint& c : exact) points.push_back(c.p_lidar + test::RandomVector(rng, point_noise));
    s.scans.push_back(points);
  }
  return s;
}

WindowOptions TestOptions(int window_size, const Pose3& T_imu_lidar) {
  WindowOptions o;
  o.smoother.window_size = window_size;
  o.smoother.association_rounds = 1;
  o.smoother.max_solver_iterations = 30;
  o.smoother.sliding_window_huber_delta = 1e3;  // no robust reweighting: the cost is one fixed function
  o.smoother.reassociate_min_motion = 0.0;
  o.smoother.linear_solver = "dense_schur";
  o.rv.enabled = false;
  o.imu.gyro_noise_density = 2e-3 / std::sqrt(400.0);
  o.imu.accel_noise_density = 2e-2 / std::sqrt(400.0);
  o.imu.gyro_bias_random_walk = 1e-4;
  o.imu.accel_bias_random_walk = 1e-3;
  o.constraints.lidar_noise = 0.02;
  o.g_world = test::Gravity();
  const Eigen::Quaterniond q = T_imu_lidar.quaternion();
  o.extrinsics.imu_T_lidar.translation = {T_imu_lidar.t.x(), T_imu_lidar.t.y(), T_imu_lidar.t.z()};
  o.extrinsics.imu_T_lidar.rotation_xyzw = {q.x(), q.y(), q.z(), q.w()};
  return o;
}

// Drives a window through the sequence like the odometry does: predict the
// new state by IMU integration from the newest estimate, add it with its
// preintegration, optimize, marginalize when full. `no_imu` lists the
// states added without an IMU factor.
class Driver {
 public:
  Driver(const WindowOptions& options, const Sequence& seq) : window_(options), seq_(seq) {
    associate_ = [this](const std::vector<Vector3d>& p, const Pose3& T, ConstraintList* out) {
      BoxAssociate(ImuTLidar(window_.options().extrinsics), p, T, out);
    };
  }

  void Start() {
    const TimeNs t = kT0;
    window_.Start(t, test::TruePose(t), test::TrueSpeedBias(t, Vector3d::Zero(), Vector3d::Zero()),
                  seq_.scans[0]);
    window_.Optimize(associate_);
  }

  // Adds state k (>= 1) at time t_ns (default: its scan time).
  WindowSolveReport Step(int k, bool with_imu = true, TimeNs t_ns = -1) {
    const TimeNs t = t_ns >= 0 ? t_ns : kT0 + k * kScanNs;
    const WindowState last = window_.state(window_.size() - 1);
    ImuKinematics x;
    x.t_ns = last.t_ns;
    x.R_world_imu = last.pose.q_world_imu.toRotationMatrix();
    x.p_world_imu = last.pose.p_world_imu;
    x.v_world_imu = last.speed_bias.v_world_imu;
    const Vector3d& bg = last.speed_bias.bg;
    const Vector3d& ba = last.speed_bias.ba;
    const ImuKinematics pred = Integrate(x, seq_.imu, t, bg, ba, test::Gravity());
    std::optional<ImuPreintegration> pre;
    if (with_imu)
      pre = ImuPreintegration::FromSamples(seq_.imu, last.t_ns, t,
                                           ImuNoise::FromOptions(window_.options().imu), bg, ba);
    SpeedBiasBlock sb;
    sb.v_world_imu = pred.v_world_imu;
    sb.bg = bg;
    sb.ba = ba;
    window_.Add(t, PoseBlock(Eigen::Quaterniond(pred.R_world_imu), pred.p_world_imu), sb,
                std::move(pre), seq_.scans[k]);
    const WindowSolveReport report = window_.Optimize(associate_);
    if (window_.MarginalizeIfFull()) ++marginalized_;
    return report;
  }

  SlidingWindow& window() { return window_; }
  WindowState newest() const { return window_.state(window_.size() - 1); }
  int marginalized() const { return marginalized_; }
  const ScanAssociateFn& associate() const { return associate_; }

 private:
  SlidingWindow window_;
  const Sequence& seq_;
  ScanAssociateFn associate_;
  int marginalized_ = 0;
};

struct StateError {
  double rot, pos, vel, bg, ba;
};

StateError Difference(const WindowState& a, const WindowState& b) {
  const auto d = Minus(a.pose, b.pose);
  return {d.head<3>().norm(), d.tail<3>().norm(),
          (a.speed_bias.v_world_imu - b.speed_bias.v_world_imu).norm(),
          (a.speed_bias.bg - b.speed_bias.bg).norm(), (a.speed_bias.ba - b.speed_bias.ba).norm()};
}

const Pose3 kImuLidar(test::Rz(0.2), Vector3d(0.05, 0.0, 0.1));

TEST(SlidingWindowMarginalization, MatchesABatchSolveOverTheSameData) {
  constexpr int kStates = 14;
  const Sequence seq = MakeSequence(kStates, 21, kImuLidar, 0.02, Vector3d(3e-3, -2e-3, 1e-3),
                                    Vector3d(0.05, -0.03, 0.02));
  Driver window(TestOptions(4, kImuLidar), seq);
  Driver batch(TestOptions(100, kImuLidar), seq);  // never marginalizes
  window.Start();
  batch.Start();
  for (int k = 1; k < kStates; ++k) {
    window.Step(k);
    batch.Step(k);
  }
  // Both converged on the last state: compare it (the window's earlier
  // states have left through the prior).
  window.window().Optimize(window.associate());
  batch.window().Optimize(batch.associate());
  EXPECT_EQ(window.marginalized(), kStates - 3);
  EXPECT_EQ(window.window().size(), 3);
  EXPECT_EQ(batch.window().size(), kStates);
  EXPECT_EQ(window.window().stats().marginalization_failures, 0);

  const WindowState w = window.newest(), b = batch.newest();
  const StateError diff = Difference(w, b);
  const StateError err = Difference(b, {b.t_ns, test::TruePose(b.t_ns),
                                        test::TrueSpeedBias(b.t_ns, seq.bg, seq.ba)});
  // The batch estimate carries the noise (errors: rot 5.7e-4 rad, pos 1.6e-3 m,
  // vel 1.3e-2 m/s); the marginalized window agrees with it two orders of
  // magnitude more closely (measured: rot 3.4e-6 rad, pos 7.0e-6 m, vel
  // 5.1e-5 m/s, bg 2.1e-6 rad/s, ba 7.7e-5 m/s^2; not zero because the prior
  // keeps the Jacobians of its linearization point).
  EXPECT_LT(diff.rot, 2e-5);
  EXPECT_LT(diff.pos, 5e-5);
  EXPECT_LT(diff.vel, 3e-4);
  EXPECT_LT(diff.bg, 2e-5);
  EXPECT_LT(diff.ba, 5e-4);
  EXPECT_LT(diff.rot, 0.05 * err.rot);
  EXPECT_LT(diff.pos, 0.05 * err.pos);
  EXPECT_LT(diff.vel, 0.05 * err.vel);
  EXPECT_GT(err.pos, 1e-4);  // the noise does move the estimate: the comparison means something
}

TEST(SlidingWindowMarginalization, EvenAWindowOfTwoMatchesTheBatch) {
  // The smallest window keeps all earlier information in its prior alone.
  constexpr int kStates = 14;
  const Sequence seq = MakeSequence(kStates, 22, kImuLidar, 0.02, Vector3d(3e-3, -2e-3, 1e-3),
                                    Vector3d(0.05, -0.03, 0.02));
  Driver small(TestOptions(2, kImuLidar), seq);
  Driver batch(TestOptions(100, kImuLidar), seq);
  small.Start();
  batch.Start();
  for (int k = 1; k < kStates; ++k) {
    small.Step(k);
    batch.Step(k);
  }
  small.window().Optimize(small.associate());
  batch.window().Optimize(batch.associate());
  EXPECT_EQ(small.window().size(), 1);
  const StateError diff = Difference(small.newest(), batch.newest());
  // Measured: pos 3.2e-5 m, rot 1.2e-6 rad, vel 8.9e-5 m/s.
  EXPECT_LT(diff.pos, 1.5e-4);
  EXPECT_LT(diff.rot, 1e-5);
  EXPECT_LT(diff.vel, 5e-4);
}

TEST(SlidingWindowGaps, StatesWithoutAnImuFactorStaySolvable) {
  constexpr int kStates = 10;
  const Sequence seq = MakeSequence(kStates, 5, kImuLidar, 0.01, Vector3d::Zero(), Vector3d::Zero());
  Driver d(TestOptions(4, kImuLidar), seq);
  d.Start();
  for (int k = 1; k < kStates; ++k) {
    const bool gap = (k == 3);
    const WindowSolveReport r = d.Step(k, !gap);
    ASSERT_TRUE(r.ok) << k;
    if (gap) {
      EXPECT_FALSE(d.window().has_imu_factor(d.window().size() - 1));
    }
    const StateError e = Difference(d.newest(), {0, test::TruePose(d.newest().t_ns), {}});
    EXPECT_LT(e.pos, 0.01) << k;  // the box room pins every pose
    EXPECT_LT(e.rot, 2e-3) << k;
  }
  // A zero interval (a second scan at the same time) is a gap as well.
  const WindowState last = d.newest();
  ASSERT_TRUE(d.Step(kStates - 1, true, last.t_ns).ok);
  EXPECT_FALSE(d.window().has_imu_factor(d.window().size() - 1));
  EXPECT_EQ(d.window().stats().imu_factors_skipped, 2);
  EXPECT_EQ(d.window().stats().marginalization_failures, 0);
  for (int k = 0; k < d.window().size(); ++k) {
    const WindowState s = d.window().state(k);
    EXPECT_TRUE(s.speed_bias.v_world_imu.allFinite() && s.pose.p_world_imu.allFinite());
    EXPECT_LT((s.speed_bias.v_world_imu - test::Swing(NsToSeconds(s.t_ns)).v).norm(), 0.1) << k;
  }
}

// Snapshot of every state of a window.
std::vector<WindowState> Snapshot(const SlidingWindow& w) {
  std::vector<WindowState> out;
  for (int k = 0; k < w.size(); ++k) out.push_back(w.state(k));
  return out;
}

void ExpectSameStates(const std::vector<WindowState>& a, const std::vector<WindowState>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].pose.p_world_imu, b[k].pose.p_world_imu) << k;
    EXPECT_EQ(a[k].pose.q_world_imu.coeffs(), b[k].pose.q_world_imu.coeffs()) << k;
    EXPECT_EQ(a[k].speed_bias.v_world_imu, b[k].speed_bias.v_world_imu) << k;
  }
}

TEST(SlidingWindowFailure, AbsurdAssociationsNeverReachTheSolution) {
  constexpr int kStates = 8;
  const Sequence seq = MakeSequence(kStates, 9, kImuLidar, 0.01, Vector3d::Zero(), Vector3d::Zero());
  WindowOptions options = TestOptions(5, kImuLidar);
  options.smoother.sliding_window_huber_delta = 1e300;  // let an absurd residual through unweighted
  Driver d(options, seq);
  d.Start();
  for (int k = 1; k < kStates; ++k) ASSERT_TRUE(d.Step(k).ok);
  // A corrupt association (finite numbers): a plane point 1e300 m away; its
  // squared residual overflows the scan's summary.
  int corrupted = 0;
  const ScanAssociateFn corrupt = [&](const std::vector<Vector3d>& p, const Pose3& T,
                                      ConstraintList* out) {
    d.associate()(p, T, out);
    out->front().q_world = Vector3d::Constant(1e300);
    ++corrupted;
  };
  const WindowSolveReport r = d.window().Optimize(corrupt);
  ASSERT_GT(corrupted, 0);  // the solves moved the states: they are re-associated
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(d.window().stats().rejected_scans, corrupted);
  EXPECT_EQ(d.window().stats().solve_failures, 0);
  // Without their scans the states rest on the IMU and the prior: finite, close.
  for (const WindowState& s : Snapshot(d.window())) {
    EXPECT_TRUE(s.pose.p_world_imu.allFinite() && s.speed_bias.v_world_imu.allFinite());
    EXPECT_LT(Minus(s.pose, test::TruePose(s.t_ns)).tail<3>().norm(), 0.05);
  }
  // Rejected scans are associated again: with sane data the window is back.
  EXPECT_TRUE(d.window().Optimize(d.associate()).ok);
  for (int k = 0; k < d.window().size(); ++k)
    EXPECT_EQ(d.window().constraints(k).size(), seq.scans[0].size()) << k;
  for (const WindowState& s : Snapshot(d.window()))
    EXPECT_LT(Minus(s.pose, test::TruePose(s.t_ns)).tail<3>().norm(), 0.01);
}

// Adds state t = newest + 100 ms with a preintegration of `imu` (initial
// values from the clean samples).
void AddState(Driver* d, const Sequence& seq, const std::vector<ImuSample>& imu,
              const std::vector<Vector3d>& scan) {
  const WindowState last = d->newest();
  const TimeNs t = last.t_ns + kScanNs;
  const ImuKinematics pred = Integrate({last.t_ns, last.pose.q_world_imu.toRotationMatrix(),
                                        last.pose.p_world_imu, last.speed_bias.v_world_imu},
                                       seq.imu, t, last.speed_bias.bg, last.speed_bias.ba,
                                       test::Gravity());
  d->window().Add(t, PoseBlock(Eigen::Quaterniond(pred.R_world_imu), pred.p_world_imu),
                  SpeedBiasBlock{pred.v_world_imu, last.speed_bias.bg, last.speed_bias.ba},
                  ImuPreintegration::FromSamples(imu, last.t_ns, t,
                                                 ImuNoise::FromOptions(d->window().options().imu),
                                                 last.speed_bias.bg, last.speed_bias.ba),
                  scan);
}

// A burst of corrupt (finite) accelerometer samples in (t0, t1): the IMU
// factor over it asks for a speed of ~1000 m/s, above max_speed.
std::vector<ImuSample> WithAccBurst(std::vector<ImuSample> imu, TimeNs t0, TimeNs t1) {
  for (ImuSample& m : imu)
    if (m.t_ns > t0 && m.t_ns < t1) m.acc_imu.x() += 1e4;
  return imu;
}

TEST(SlidingWindowFailure, DivergedSolveIsRedoneWithoutTheNewestImuFactor) {
  constexpr int kStates = 6;
  const Sequence seq = MakeSequence(kStates, 13, kImuLidar, 0.01, Vector3d::Zero(), Vector3d::Zero());
  Driver d(TestOptions(10, kImuLidar), seq);
  d.Start();
  for (int k = 1; k + 1 < kStates; ++k) ASSERT_TRUE(d.Step(k).ok);
  const TimeNs t0 = d.newest().t_ns;
  AddState(&d, seq, WithAccBurst(seq.imu, t0, t0 + kScanNs), seq.scans[kStates - 1]);
  ASSERT_TRUE(d.window().has_imu_factor(d.window().size() - 1));
  const WindowSolveReport r = d.window().Optimize(d.associate());
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(r.failures, 1);
  EXPECT_TRUE(r.dropped_newest_imu);
  EXPECT_EQ(d.window().stats().solve_failures, 1);
  EXPECT_EQ(d.window().stats().imu_factors_skipped, 1);
  EXPECT_FALSE(d.window().has_imu_factor(d.window().size() - 1));
  for (const WindowState& s : Snapshot(d.window())) {
    EXPECT_LT(s.speed_bias.v_world_imu.norm(), 5.0);
    EXPECT_LT(Minus(s.pose, test::TruePose(s.t_ns)).tail<3>().norm(), 0.01);
  }
}

TEST(SlidingWindowFailure, RepeatedDivergenceRestoresTheLastGoodState) {
  constexpr int kStates = 7;
  const Sequence seq = MakeSequence(kStates, 14, kImuLidar, 0.01, Vector3d::Zero(), Vector3d::Zero());
  Driver d(TestOptions(10, kImuLidar), seq);
  d.Start();
  for (int k = 1; k + 2 < kStates; ++k) ASSERT_TRUE(d.Step(k).ok);
  // Two corrupt intervals: dropping the newest one is not enough.
  const TimeNs t0 = d.newest().t_ns;
  const std::vector<ImuSample> corrupt = WithAccBurst(seq.imu, t0, t0 + 2 * kScanNs);
  AddState(&d, seq, corrupt, seq.scans[kStates - 2]);
  AddState(&d, seq, corrupt, seq.scans[kStates - 1]);
  const std::vector<WindowState> before = Snapshot(d.window());
  const WindowSolveReport r = d.window().Optimize(d.associate());
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.failures, 2);
  EXPECT_EQ(d.window().stats().solve_failures, 2);
  ExpectSameStates(Snapshot(d.window()), before);
  for (const WindowState& s : Snapshot(d.window())) EXPECT_TRUE(s.speed_bias.v_world_imu.allFinite());
}

TEST(SlidingWindowShortSequence, FewerStatesThanTheWindowNeverMarginalize) {
  const Sequence seq = MakeSequence(3, 17, kImuLidar, 0.01, Vector3d::Zero(), Vector3d::Zero());
  Driver d(TestOptions(10, kImuLidar), seq);
  d.Start();
  EXPECT_EQ(d.window().size(), 1);
  for (int k = 1; k < 3; ++k) EXPECT_TRUE(d.Step(k).ok);
  EXPECT_EQ(d.marginalized(), 0);
  EXPECT_FALSE(d.window().MarginalizeIfFull().has_value());
  EXPECT_LT(Difference(d.newest(), {0, test::TruePose(d.newest().t_ns), {}}).pos, 0.01);
}

// Rounds after the first: with smoother.solve_unchanged_rounds = false a round
// that re-associates no scan ends Optimize, so the window equals one that
// runs a single round; a round that does re-associate is solved either way.
TEST(SlidingWindowRounds, ARoundWithoutNewAssociationsEndsOptimize) {
  constexpr int kStates = 8;
  const Sequence seq = MakeSequence(kStates, 41, kImuLidar, 0.01, Vector3d::Zero(), Vector3d::Zero());
  const auto run = [&seq](int rounds, double min_motion, bool solve_unchanged,
                          std::vector<WindowSolveReport>* reports) {
    WindowOptions o = TestOptions(5, kImuLidar);
    o.smoother.association_rounds = rounds;
    o.smoother.max_solver_iterations = 3;  // not converged in one round: another solve moves it
    o.smoother.reassociate_min_motion = min_motion;
    o.smoother.solve_unchanged_rounds = solve_unchanged;
    auto d = std::make_unique<Driver>(o, seq);
    d->Start();
    for (int k = 1; k < kStates; ++k) reports->push_back(d->Step(k));
    return d;
  };
  std::vector<WindowSolveReport> one, skip, solve_all, moving;
  // min_motion 10 m: nothing is associated again after its first round.
  const auto single = run(1, 10.0, false, &one);
  const auto skipped = run(3, 10.0, false, &skip);
  const auto repeated = run(3, 10.0, true, &solve_all);
  for (int k = 0; k < kStates - 1; ++k) {
    EXPECT_EQ(skip[k].rounds, 1) << k;
    EXPECT_EQ(solve_all[k].rounds, 3) << k;
    EXPECT_EQ(skip[k].associations, one[k].associations) << k;
    EXPECT_EQ(skip[k].iterations, one[k].iterations) << k;
    EXPECT_GT(solve_all[k].iterations, one[k].iterations) << k;
  }
  for (int i = 0; i < single->window().size(); ++i) {
    const StateError same = Difference(skipped->window().state(i), single->window().state(i));
    EXPECT_EQ(same.rot, 0.0) << i;
    EXPECT_EQ(same.pos, 0.0) << i;
    EXPECT_EQ(same.vel, 0.0) << i;
  }
  // The extra solves of the repeated rounds do move the states.
  EXPECT_GT(Difference(repeated->newest(), single->newest()).pos, 0.0);
  // min_motion 0: every round re-associates every scan, so every round is solved.
  run(3, 0.0, false, &moving);
  for (const WindowSolveReport& r : moving) EXPECT_EQ(r.rounds, 3);
}

// smoother.function_tolerance reaches Ceres: a loose tolerance stops the
// solves earlier (fewer iterations) than the default 1e-6.
TEST(SlidingWindowRounds, FunctionToleranceStopsTheSolvesEarlier) {
  constexpr int kStates = 6;
  const Sequence seq = MakeSequence(kStates, 43, kImuLidar, 0.01, Vector3d::Zero(), Vector3d::Zero());
  const auto iterations = [&seq](double tolerance) {
    WindowOptions o = TestOptions(5, kImuLidar);
    o.smoother.function_tolerance = tolerance;
    Driver d(o, seq);
    d.Start();
    int total = 0;
    for (int k = 1; k < kStates; ++k) total += d.Step(k).iterations;
    return total;
  };
  const int tight = iterations(1e-6), loose = iterations(1e-2);
  EXPECT_GT(loose, 0);
  EXPECT_LT(loose, tight);
}

TEST(SlidingWindowImu, BiasesAreEstimatedAndPreintegrationsReintegrated) {
  constexpr int kStates = 16;
  const Vector3d bg(0.02, -0.015, 0.01), ba(0.3, -0.2, 0.15);  // large: first order is not enough
  const Sequence seq = MakeSequence(kStates, 31, kImuLidar, 0.005, bg, ba);
  WindowOptions options = TestOptions(8, kImuLidar);
  options.ieskf.init_bias_gyro_std = 0.1;  // the estimate starts at zero bias
  options.ieskf.init_bias_acc_std = 1.0;
  Driver d(options, seq);
  d.Start();
  for (int k = 1; k < kStates; ++k) ASSERT_TRUE(d.Step(k).ok);
  EXPECT_GT(d.window().stats().repropagations, 0);
  const WindowState s = d.newest();
  // Measured: |bg error| 2.2e-4 rad/s, |ba error| 2.2e-3 m/s^2.
  EXPECT_LT((s.speed_bias.bg - bg).norm(), 1e-3);
  EXPECT_LT((s.speed_bias.ba - ba).norm(), 1e-2);
}

TEST(SlidingWindowRv, RvEditsTheConstraintsOfEveryScanInACorridor) {
  // In a long corridor (walls, floor and ceiling parallel to x) every normal
  // is perpendicular to the axis: the criterion fires; repair and
  // reinforcement mark the records.
  constexpr int kStates = 4;
  const Sequence seq = MakeSequence(kStates, 41, kImuLidar, 0.01, Vector3d::Zero(), Vector3d::Zero());
  WindowOptions options = TestOptions(10, kImuLidar);
  options.rv.enabled = true;
  options.rv.eps0 = 0.5;
  options.rv.eps1 = 0.1;
  Driver d(options, seq);
  // Keep only the points on the y and z walls: a corridor along x.
  const ScanAssociateFn corridor = [&](const std::vector<Vector3d>& p, const Pose3& T,
                                       ConstraintList* out) {
    d.associate()(p, T, out);
    ConstraintList kept;
    for (const Constraint& c : *out)
      if (std::abs(c.normal_world.x()) < 0.5) kept.push_back(c);
    // Tilt a few normals slightly out of the plane alpha (the y-z plane's
    // normal is x): the repair pulls them back.
    for (size_t i = 0; i < kept.size(); i += 10)
      kept[i].normal_world = (kept[i].normal_world + Vector3d(0.05, 0.0, 0.0)).normalized();
    *out = kept;
  };
  d.Start();
  const WindowSolveReport r = d.window().Optimize(corridor);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(r.newest_rv.active);
  EXPECT_GT(r.newest_rv.num_repaired, 0);
  int repaired = 0;
  for (const Constraint& c : d.window().constraints(0)) {
    if (c.role != RvRole::kRepaired) continue;
    ++repaired;
    EXPECT_LT(std::abs(c.normal_world.dot(r.newest_rv.n_alpha)), 1e-9);  // in the plane alpha
  }
  EXPECT_EQ(repaired, r.newest_rv.num_repaired);
}

}  // namespace
}  // namespace rvlio

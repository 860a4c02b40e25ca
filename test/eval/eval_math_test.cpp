// Pure-math tests of eval/: statistics, association, Umeyama, alignment
// fallback and the metrics. Links only rvlio_eval.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/eval/align.h"
#include "rvlio/eval/time_matching.h"
#include "rvlio/eval/evaluate.h"
#include "rvlio/eval/metrics.h"
#include "rvlio/eval/stats.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

Eigen::Quaterniond RandomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
}

Eigen::Vector3d RandomVector(std::mt19937& rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return Eigen::Vector3d(n(rng), n(rng), n(rng));
}

// A wandering 3D trajectory at 10 Hz with changing orientation.
Trajectory RandomTrajectory(std::mt19937& rng, size_t n) {
  Trajectory t(n);
  Eigen::Vector3d p = RandomVector(rng, 1.0);
  Eigen::Quaterniond q = RandomRotation(rng);
  for (size_t i = 0; i < n; ++i) {
    t[i].t_ns = static_cast<TimeNs>(i) * 100000000;
    p += RandomVector(rng, 0.3);
    const Eigen::Vector3d w = RandomVector(rng, 0.1);
    q = (q * Eigen::Quaterniond(Eigen::AngleAxisd(w.norm(), w.normalized()))).normalized();
    t[i].p_world_imu = p;
    t[i].q_world_imu = q;
  }
  return t;
}

Similarity3 RandomSimilarity(std::mt19937& rng, bool with_scale) {
  Similarity3 T;
  T.R_ref_est = RandomRotation(rng).toRotationMatrix();
  T.t_ref_est = RandomVector(rng, 10.0);
  if (with_scale) T.scale = std::exp(std::uniform_real_distribution<double>(-1.5, 1.5)(rng));
  return T;
}

// ---------------------------------------------------------------- statistics

TEST(Stats, EvenCountMatchesNumpyDefinitions) {
  const ErrorStats s = ComputeStats({4.0, 1.0, 3.0, 2.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);  // mean of the two middle values
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));  // population (ddof = 0)
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
}

TEST(Stats, OddCountAndSingleValue) {
  const ErrorStats s = ComputeStats({3.0, 1.0, 2.0, 10.0, 0.5});
  EXPECT_DOUBLE_EQ(s.median, 2.0);
  EXPECT_DOUBLE_EQ(s.mean, 3.3);
  const ErrorStats one = ComputeStats({0.7});
  EXPECT_DOUBLE_EQ(one.rmse, 0.7);
  EXPECT_DOUBLE_EQ(one.std, 0.0);
  EXPECT_DOUBLE_EQ(one.median, 0.7);
  EXPECT_EQ(ComputeStats({}).count, 0u);
}

TEST(Stats, RmseSquaredIsMeanSquaredPlusVariance) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 5.0);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<double> v(1 + rng() % 40);
    for (double& x : v) x = u(rng);
    const ErrorStats s = ComputeStats(v);
    EXPECT_NEAR(s.rmse * s.rmse, s.mean * s.mean + s.std * s.std, 1e-10);
    EXPECT_LE(s.min, s.median);
    EXPECT_LE(s.median, s.max);
  }
}

// --------------------------------------------------------------- association

Trajectory Stamps(const std::vector<TimeNs>& t) {
  Trajectory out(t.size());
  for (size_t i = 0; i < t.size(); ++i) out[i].t_ns = t[i];
  return out;
}

// numpy.argmin(|long - t|) over double seconds: the first of equally near.
size_t BruteNearest(const Trajectory& longer, TimeNs t) {
  const auto diff = [&](size_t j) {
    return std::fabs(StampSeconds(longer[j].t_ns) - StampSeconds(t));
  };
  size_t best = 0;
  for (size_t j = 1; j < longer.size(); ++j)
    if (diff(j) < diff(best)) best = j;
  return best;
}

TEST(Associate, MatchesLinearArgminOverRandomTrials) {
  std::mt19937 rng(11);
  constexpr TimeNs kBase = 1311868226000000000LL;  // realistic stamps: ties break as in numpy
  constexpr TimeNs kMs = 1000000;
  int ties = 0;
  for (int trial = 0; trial < 300; ++trial) {
    // Steps of 0..3 ms create exact decimal ties and repeated stamps.
    std::vector<TimeNs> a(1 + rng() % 30), b(1 + rng() % 30);
    TimeNs t = kBase + (rng() % 5) * kMs;
    for (TimeNs& x : a) x = (t += (rng() % 4) * kMs);
    t = kBase + (rng() % 5) * kMs;
    for (TimeNs& x : b) x = (t += (rng() % 4) * kMs + (rng() % 2) * kMs / 2);
    const Trajectory ref = Stamps(a), est = Stamps(b);
    const double max_dt = (rng() % 3) * 1e-3;
    StatusOr<Association> assoc = Associate(ref, est, max_dt);
    const bool est_longer = est.size() > ref.size();
    const Trajectory& shorter = est_longer ? ref : est;
    const Trajectory& longer = est_longer ? est : ref;
    std::vector<size_t> expect_short, expect_long;
    for (size_t i = 0; i < shorter.size(); ++i) {
      const size_t j = BruteNearest(longer, shorter[i].t_ns);
      if (j > 0 && std::llabs(longer[j - 1].t_ns - shorter[i].t_ns) ==
                       std::llabs(longer[j].t_ns - shorter[i].t_ns))
        ++ties;
      if (std::fabs(StampSeconds(longer[j].t_ns) - StampSeconds(shorter[i].t_ns)) <= max_dt) {
        expect_short.push_back(i);
        expect_long.push_back(j);
      }
    }
    if (expect_short.empty()) {
      EXPECT_FALSE(assoc.ok());
      continue;
    }
    ASSERT_TRUE(assoc.ok()) << assoc.status().message();
    EXPECT_EQ(est_longer ? assoc->ref_index : assoc->est_index, expect_short);
    EXPECT_EQ(est_longer ? assoc->est_index : assoc->ref_index, expect_long);
  }
  EXPECT_GT(ties, 10);  // the trials did exercise tie breaking
}

TEST(Associate, DecimalTiesBreakInDoubleSecondsLikeEvo) {
  // From the fr2_desk fixture: the estimate stamp 1311868226.310950 is exactly
  // 1.65 ms from both 226.3093 and 226.3126; in double seconds the later one is
  // nearer, and evo (numpy) takes it. Exact-nanosecond ties would take the first.
  const Trajectory ref =
      Stamps({1311868226309300000LL, 1311868226312600000LL, 1311868226400000000LL});
  const Trajectory est = Stamps({1311868226310950000LL});
  StatusOr<Association> a = Associate(ref, est, 0.01);
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->ref_index, (std::vector<size_t>{1}));
  EXPECT_EQ(StampSeconds(1311868226310950000LL), 1311868226.310950);
  EXPECT_EQ(StampSeconds(-1500000000LL), -1.5);
}

TEST(Associate, ShorterTrajectoryDrivesAndPairsAreNotOneToOne) {
  // Reference is shorter: each reference stamp takes its nearest estimate.
  // Units of 0.25 s keep the double differences exact (true ties).
  const auto q = [](std::vector<TimeNs> v) {
    for (TimeNs& x : v) x *= 250000000;
    return Stamps(v);
  };
  const Trajectory ref = q({100, 104});
  const Trajectory est = q({99, 101, 102, 103, 110});
  StatusOr<Association> a = Associate(ref, est, 5 * 0.25);
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->ref_index, (std::vector<size_t>{0, 1}));
  EXPECT_EQ(a->est_index, (std::vector<size_t>{0, 3}));  // tie 99/101 -> first, 103 nearest 104
  // Estimate shorter: two estimate stamps share one reference partner.
  const Trajectory ref2 = q({0, 100, 200});
  const Trajectory est2 = q({95, 105});
  a = Associate(ref2, est2, 10 * 0.25);
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->ref_index, (std::vector<size_t>{1, 1}));
  EXPECT_EQ(a->est_index, (std::vector<size_t>{0, 1}));
}

TEST(Associate, ToleranceIsInclusiveAndEqualLengthsIterateTheEstimate) {
  const Trajectory ref = Stamps({0, 500000000});
  const Trajectory est = Stamps({250000000, 760000000});
  StatusOr<Association> a = Associate(ref, est, 0.25);
  ASSERT_TRUE(a.ok());
  ASSERT_EQ(a->size(), 1u);  // 0.25 s kept (inclusive), 0.26 s dropped
  EXPECT_EQ(a->est_index[0], 0u);
  EXPECT_EQ(a->ref_index[0], 0u);  // tie 0 / 0.5 s: the first
}

TEST(Associate, RejectsEmptyUnorderedAndDisjoint) {
  EXPECT_FALSE(Associate(Stamps({}), Stamps({1}), 0.01).ok());
  StatusOr<Association> a = Associate(Stamps({5, 3}), Stamps({1, 2}), 0.01);
  ASSERT_FALSE(a.ok());
  EXPECT_NE(a.status().message().find("earlier"), std::string::npos);
  a = Associate(Stamps({0, 1}), Stamps({1000000000, 2000000000}), 0.01);
  ASSERT_FALSE(a.ok());
  EXPECT_NE(a.status().message().find("no matching timestamps"), std::string::npos);
}

// ------------------------------------------------------------------- Umeyama

Eigen::Matrix3Xd Transform(const Similarity3& T, const Eigen::Matrix3Xd& x) {
  Eigen::Matrix3Xd y(3, x.cols());
  for (int i = 0; i < x.cols(); ++i) y.col(i) = T * Eigen::Vector3d(x.col(i));
  return y;
}

void ExpectSimilarityNear(const Similarity3& a, const Similarity3& b, double tol) {
  EXPECT_LT((a.R_ref_est - b.R_ref_est).norm(), tol);
  EXPECT_LT((a.t_ref_est - b.t_ref_est).norm(), tol * (1.0 + b.t_ref_est.norm()));
  EXPECT_NEAR(a.scale, b.scale, tol * b.scale);
}

TEST(Umeyama, RecoversRandomSe3AndSim3Exactly) {
  std::mt19937 rng(2024);
  for (int trial = 0; trial < 200; ++trial) {
    const bool with_scale = trial % 2 == 1;
    const int n = 3 + static_cast<int>(rng() % 60);
    Eigen::Matrix3Xd x(3, n);
    for (int i = 0; i < n; ++i) x.col(i) = RandomVector(rng, 5.0);
    const Similarity3 truth = RandomSimilarity(rng, with_scale);
    StatusOr<Similarity3> T = Umeyama(x, Transform(truth, x), with_scale);
    ASSERT_TRUE(T.ok()) << T.status().message();
    ExpectSimilarityNear(*T, truth, 1e-9);
    EXPECT_NEAR(T->R_ref_est.determinant(), 1.0, 1e-12);
  }
}

TEST(Umeyama, PlanarPointsAreEnoughAndReflectionsAreAvoided) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 50; ++trial) {
    Eigen::Matrix3Xd x(3, 20);
    for (int i = 0; i < 20; ++i)
      x.col(i) =
          Eigen::Vector3d(RandomVector(rng, 3.0).head<2>().x(), RandomVector(rng, 3.0).y(), 0.0);
    const Similarity3 truth = RandomSimilarity(rng, false);
    StatusOr<Similarity3> T = Umeyama(x, Transform(truth, x), false);
    ASSERT_TRUE(T.ok());
    ExpectSimilarityNear(*T, truth, 1e-9);
  }
}

TEST(Umeyama, IsLeastSquaresOptimalUnderNoise) {
  std::mt19937 rng(99);
  const auto cost = [](const Similarity3& T, const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& y) {
    return (Transform(T, x) - y).squaredNorm();
  };
  for (int trial = 0; trial < 30; ++trial) {
    const bool with_scale = trial % 2 == 0;
    Eigen::Matrix3Xd x(3, 40);
    for (int i = 0; i < 40; ++i) x.col(i) = RandomVector(rng, 4.0);
    Eigen::Matrix3Xd y = Transform(RandomSimilarity(rng, with_scale), x);
    for (int i = 0; i < 40; ++i) y.col(i) += RandomVector(rng, 0.2);
    StatusOr<Similarity3> T = Umeyama(x, y, with_scale);
    ASSERT_TRUE(T.ok());
    const double best = cost(*T, x, y);
    for (int k = 0; k < 20; ++k) {  // no nearby transform does better
      Similarity3 P = *T;
      const Eigen::Vector3d w = RandomVector(rng, 1e-3);
      P.R_ref_est = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix() * P.R_ref_est;
      P.t_ref_est += RandomVector(rng, 1e-3);
      if (with_scale) P.scale *= 1.0 + 1e-3 * std::normal_distribution<double>()(rng);
      EXPECT_GE(cost(P, x, y), best - 1e-12);
    }
  }
}

TEST(Umeyama, CollinearPointsAreDegenerate) {
  Eigen::Matrix3Xd x(3, 10);
  for (int i = 0; i < 10; ++i) x.col(i) = Eigen::Vector3d(1.0, 2.0, 3.0) * i;
  EXPECT_FALSE(Umeyama(x, x, false).ok());
  EXPECT_FALSE(Umeyama(x, x, true).ok());
}

// --------------------------------------------------------------- alignment

TEST(Align, OriginMapsTheFirstPoseExactly) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    const Trajectory ref = RandomTrajectory(rng, 5);
    const Trajectory est = RandomTrajectory(rng, 5);
    const AlignmentResult a = Align(ref, est, AlignMode::kOrigin);
    const StampedPose p = a.T_ref_est.Apply(est[0]);
    EXPECT_LT((p.p_world_imu - ref[0].p_world_imu).norm(), 1e-9);
    EXPECT_LT(p.q_world_imu.angularDistance(ref[0].q_world_imu), 1e-9);
    EXPECT_TRUE(a.warnings.empty());
  }
}

TEST(Align, Se3AndSim3RemoveARigidOrSimilarityTransform) {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 40; ++trial) {
    const bool with_scale = trial % 2 == 0;
    const Trajectory ref = RandomTrajectory(rng, 60);
    const Similarity3 T = RandomSimilarity(rng, with_scale);
    // est = T^-1 applied to ref, so that aligning est onto ref recovers T.
    Similarity3 T_inv;
    T_inv.R_ref_est = T.R_ref_est.transpose();
    T_inv.scale = 1.0 / T.scale;
    T_inv.t_ref_est = -(T_inv.scale * (T_inv.R_ref_est * T.t_ref_est));
    const Trajectory est = T_inv.Apply(ref);
    const AlignmentResult a = Align(ref, est, with_scale ? AlignMode::kSim3 : AlignMode::kSe3);
    EXPECT_EQ(a.used, a.requested);
    ExpectSimilarityNear(a.T_ref_est, T, 1e-8);
    const Trajectory aligned = a.T_ref_est.Apply(est);
    EXPECT_LT(ComputeStats(ApeTranslationErrors(ref, aligned)).max, 1e-8);
    EXPECT_LT(ComputeStats(ApeRotationErrorsDeg(ref, aligned)).max, 1e-6);
  }
}

Trajectory StraightLine(size_t n, double lateral_noise, std::mt19937& rng) {
  Trajectory t(n);
  for (size_t i = 0; i < n; ++i) {
    t[i].t_ns = static_cast<TimeNs>(i) * 100000000;
    t[i].p_world_imu = Eigen::Vector3d(0.5 * i, 0.0, 0.0) + RandomVector(rng, lateral_noise);
  }
  return t;
}

TEST(Align, CollinearReferenceFallsBackToOriginWithWarning) {
  std::mt19937 rng(8);
  const Trajectory ref = StraightLine(100, 0.0, rng);
  Trajectory est = ref;
  for (StampedPose& p : est) p.p_world_imu += Eigen::Vector3d(1.0, 2.0, 3.0);
  for (AlignMode mode : {AlignMode::kSe3, AlignMode::kSim3}) {
    const AlignmentResult a = Align(ref, est, mode);
    EXPECT_EQ(a.used, AlignMode::kOrigin);
    ASSERT_EQ(a.warnings.size(), 1u);
    EXPECT_NE(a.warnings[0].find("collinear"), std::string::npos) << a.warnings[0];
    const Similarity3 origin = OriginAlignment(ref[0], est[0]);
    ExpectSimilarityNear(a.T_ref_est, origin, 1e-12);
  }
  // Lateral wobble of 1e-4 of the length is still "a line" at the default.
  const Trajectory wobbly = StraightLine(100, 0.5 * 100 * 1e-5, rng);
  EXPECT_EQ(Align(wobbly, wobbly, AlignMode::kSe3).used, AlignMode::kOrigin);
  // A real 3D trajectory keeps Umeyama.
  const Trajectory curve = RandomTrajectory(rng, 100);
  EXPECT_EQ(Align(curve, curve, AlignMode::kSe3).used, AlignMode::kSe3);
}

// On a straight path with noisy positions, Umeyama leaves the roll about the
// path to the noise; the alignment of whole poses takes it from the
// orientations and recovers a rigid transform of the estimate.
TEST(Align, PoseAlignmentRecoversTheRollAboutAStraightPath) {
  std::mt19937 rng(11);
  Trajectory ref = StraightLine(100, 0.002, rng);
  for (StampedPose& p : ref)
    p.q_world_imu = Eigen::Quaterniond(so3::Exp(RandomVector(rng, 0.05)));
  Similarity3 T;  // est = T^-1 ref: a roll of 3 degrees about the path and a shift
  T.R_ref_est = so3::Exp(Eigen::Vector3d(3.0 * M_PI / 180.0, 0.01, -0.02));
  T.t_ref_est = Eigen::Vector3d(0.4, -1.0, 0.3);
  Similarity3 T_inv;
  T_inv.R_ref_est = T.R_ref_est.transpose();
  T_inv.t_ref_est = -(T_inv.R_ref_est * T.t_ref_est);
  const Trajectory est = T_inv.Apply(ref);
  ExpectSimilarityNear(PoseAlignment(ref, est), T, 1e-9);
  // Rotation noise on the estimate's orientations leaves it close.
  Trajectory noisy = est;
  for (StampedPose& p : noisy)
    p.q_world_imu = Eigen::Quaterniond(p.q_world_imu.toRotationMatrix() *
                                       so3::Exp(RandomVector(rng, 0.002)));
  const Similarity3 A = PoseAlignment(ref, noisy);
  EXPECT_LT(so3::Log(A.R_ref_est.transpose() * T.R_ref_est).norm(), 1e-3);
}

TEST(Align, TooFewPosesFallBackToOrigin) {
  std::mt19937 rng(4);
  const Trajectory ref = RandomTrajectory(rng, 2);
  const AlignmentResult a = Align(ref, ref, AlignMode::kSim3);
  EXPECT_EQ(a.used, AlignMode::kOrigin);
  ASSERT_EQ(a.warnings.size(), 1u);
  EXPECT_NE(a.warnings[0].find("only 2 matched poses"), std::string::npos);
}

TEST(Align, LateralRatioOfKnownShapes) {
  Trajectory t(4);
  // A 2 x 1 rectangle: principal std ratio 1/2.
  t[0].p_world_imu = {1, 0.5, 0};
  t[1].p_world_imu = {-1, 0.5, 0};
  t[2].p_world_imu = {-1, -0.5, 0};
  t[3].p_world_imu = {1, -0.5, 0};
  EXPECT_NEAR(LateralRatio(t), 0.5, 1e-12);
  EXPECT_EQ(LateralRatio(Trajectory(1)), 0.0);
}

TEST(AlignModeNames, RoundTripAndReject) {
  for (AlignMode m : {AlignMode::kNone, AlignMode::kOrigin, AlignMode::kSe3, AlignMode::kSim3}) {
    StatusOr<AlignMode> parsed = ParseAlignMode(AlignModeName(m));
    ASSERT_TRUE(parsed.ok());
    EXPECT_EQ(*parsed, m);
  }
  EXPECT_FALSE(ParseAlignMode("SE3").ok());
}

// ------------------------------------------------------------------- metrics

TEST(Rpe, IdenticalTrajectoriesHaveZeroError) {
  std::mt19937 rng(21);
  const Trajectory t = RandomTrajectory(rng, 80);
  for (RpeOptions o : {RpeOptions{1.0, RpeUnit::kFrames}, RpeOptions{7.0, RpeUnit::kFrames},
                       RpeOptions{2.0, RpeUnit::kMeters}}) {
    StatusOr<RpeResult> r = ComputeRpe(t, t, o);
    ASSERT_TRUE(r.ok());
    EXPECT_GT(r->pairs, 0u);
    EXPECT_LT(r->trans_m.max, 1e-12);
    EXPECT_LT(r->rot_deg.max, 1e-9);
  }
}

TEST(Rpe, InvariantToARigidTransformOfTheEstimate) {
  std::mt19937 rng(22);
  for (int trial = 0; trial < 20; ++trial) {
    const Trajectory ref = RandomTrajectory(rng, 50);
    Trajectory est = ref;
    for (StampedPose& p : est) p.p_world_imu += RandomVector(rng, 0.05);
    const Trajectory moved = RandomSimilarity(rng, false).Apply(est);
    const RpeResult a = *ComputeRpe(ref, est, RpeOptions());
    const RpeResult b = *ComputeRpe(ref, moved, RpeOptions());
    EXPECT_NEAR(a.trans_m.rmse, b.trans_m.rmse, 1e-10);
    EXPECT_NEAR(a.rot_deg.rmse, b.rot_deg.rmse, 1e-8);
    EXPECT_GT(a.trans_m.rmse, 1e-3);
  }
}

TEST(Rpe, KnownRelativeError) {
  // Reference moves 1 m along x per frame; the estimate 1.1 m and yaws 2 deg.
  Trajectory ref(3), est(3);
  for (int i = 0; i < 3; ++i) {
    ref[i].p_world_imu = Eigen::Vector3d(i, 0, 0);
    est[i].p_world_imu = Eigen::Vector3d(1.1 * i, 0, 0);
    est[i].q_world_imu =
        Eigen::Quaterniond(Eigen::AngleAxisd(i * 2.0 * M_PI / 180, Eigen::Vector3d::UnitZ()));
  }
  StatusOr<RpeResult> r = ComputeRpe(ref, est, RpeOptions());
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->pairs, 2u);
  // Pair (1,2): P_rel translation is R(2 deg)^T (1.1, 0, 0); Q_rel = (1, 0, 0).
  const Eigen::Vector3d p_rel =
      Eigen::AngleAxisd(2.0 * M_PI / 180, Eigen::Vector3d::UnitZ()).inverse() *
      Eigen::Vector3d(1.1, 0, 0);
  EXPECT_NEAR(r->trans_m.min, 0.1, 1e-12);                                        // pair (0,1)
  EXPECT_NEAR(r->trans_m.max, (p_rel - Eigen::Vector3d(1, 0, 0)).norm(), 1e-12);  // pair (1,2)
  EXPECT_NEAR(r->rot_deg.mean, 2.0, 1e-9);
}

TEST(RpePairs, FramesUseNonOverlappingStepsLikeEvo) {
  const Trajectory t(25);
  using Pairs = std::vector<std::pair<size_t, size_t>>;
  EXPECT_EQ(RpePairs(t, {10.0, RpeUnit::kFrames}), (Pairs{{0, 10}, {10, 20}}));
  EXPECT_EQ(RpePairs(t, {1.0, RpeUnit::kFrames}).size(), 24u);
  EXPECT_TRUE(RpePairs(t, {30.0, RpeUnit::kFrames}).empty());
  StatusOr<RpeResult> r = ComputeRpe(t, t, {30.0, RpeUnit::kFrames});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("no pose pair"), std::string::npos);
}

TEST(RpePairs, MetersAccumulatePathFromTheStart) {
  Trajectory t(12);
  for (size_t i = 0; i < t.size(); ++i) t[i].p_world_imu = Eigen::Vector3d(0.4 * i, 0, 0);
  // Path reaches >= 1 m at poses 3 (1.2), then 6, 9 (reset at each id).
  using Pairs = std::vector<std::pair<size_t, size_t>>;
  EXPECT_EQ(RpePairs(t, {1.0, RpeUnit::kMeters}), (Pairs{{3, 6}, {6, 9}}));
}

TEST(Ape, RotationAngleOfKnownOffsets) {
  std::mt19937 rng(31);
  const Trajectory ref = RandomTrajectory(rng, 10);
  Trajectory est = ref;
  for (size_t i = 0; i < est.size(); ++i) {
    const double deg = 1.0 + i;
    const Eigen::Vector3d axis = RandomVector(rng, 1.0).normalized();
    est[i].q_world_imu =
        ref[i].q_world_imu * Eigen::Quaterniond(Eigen::AngleAxisd(deg * M_PI / 180, axis));
  }
  const std::vector<double> e = ApeRotationErrorsDeg(ref, est);
  for (size_t i = 0; i < e.size(); ++i) EXPECT_NEAR(e[i], 1.0 + i, 1e-9);
  EXPECT_NEAR(RotationAngle(Eigen::Quaterniond(Eigen::AngleAxisd(1e-9, Eigen::Vector3d::UnitY()))),
              1e-9, 1e-20);
  // q and -q are the same rotation.
  EXPECT_NEAR(RotationAngle(Eigen::Quaterniond(-0.5, -0.5, -0.5, -0.5)), 2.0 * M_PI / 3, 1e-12);
}

TEST(EndPointAndAlongAxis, KnownOffsets) {
  std::mt19937 rng(41);
  const Trajectory ref = StraightLine(50, 0.0, rng);
  Trajectory est = ref;
  for (size_t i = 0; i < est.size(); ++i)
    est[i].p_world_imu += Eigen::Vector3d(0.01 * i, (i % 2 ? 0.3 : -0.3), 0.0);
  EXPECT_NEAR(EndPointError(ref, est), std::hypot(0.49, 0.3), 1e-12);
  const AlongAxisError a = ComputeAlongAxisError(ref, est);
  EXPECT_NEAR(std::fabs(a.axis.x()), 1.0, 1e-12);
  EXPECT_NEAR(a.max_abs_m, 0.49, 1e-12);  // lateral offsets do not count
  double sum_sq = 0.0;
  for (int i = 0; i < 50; ++i) sum_sq += 0.0001 * i * i;
  EXPECT_NEAR(a.rmse_m, std::sqrt(sum_sq / 50), 1e-12);
}

// ------------------------------------------------------------------ pipeline

TEST(Evaluate, RigidlyMovedEstimateHasZeroApeAfterSe3) {
  std::mt19937 rng(51);
  const Trajectory ref = RandomTrajectory(rng, 100);
  Trajectory est = RandomSimilarity(rng, false).Apply(ref);
  for (StampedPose& p : est) p.t_ns += 3000000;  // 3 ms offset, within max_dt
  EvalOptions o;
  StatusOr<EvalResult> r = Evaluate(ref, est, o);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->matched, 100u);
  EXPECT_EQ(r->align, AlignMode::kSe3);
  EXPECT_LT(r->ape_m.max, 1e-8);
  EXPECT_LT(r->ape_rot_deg.max, 1e-6);
  EXPECT_LT(r->end_point_error_m, 1e-8);
  EXPECT_TRUE(r->warnings.empty());
  o.align = "none";
  r = Evaluate(ref, est, o);
  ASSERT_TRUE(r.ok());
  EXPECT_GT(r->ape_m.rmse, 1e-2);
  EXPECT_LT(r->rpe.trans_m.max, 1e-9);  // RPE does not see a rigid transform
}

TEST(Evaluate, RejectsBadOptions) {
  std::mt19937 rng(52);
  const Trajectory ref = RandomTrajectory(rng, 10);
  EvalOptions o;
  o.align = "affine";
  EXPECT_FALSE(Evaluate(ref, ref, o).ok());
  o = EvalOptions();
  o.rpe_delta = 1.5;
  StatusOr<EvalResult> r = Evaluate(ref, ref, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("whole number"), std::string::npos);
  o.rpe_unit = "meters";
  EXPECT_TRUE(Evaluate(ref, ref, o).ok());
}

}  // namespace
}  // namespace rvlio

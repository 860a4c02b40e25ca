// Scoring of a degeneracy detection against the true localizability
// (eval/degeneracy.h) on hand-built tables with known precision, recall,
// angles and error along the weak direction.
#include <cmath>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "rvlio/eval/degeneracy_scores.h"

namespace rvlio {
namespace {

constexpr TimeNs kT0 = 1'700'000'000'000'000'000;
constexpr TimeNs kPeriod = 100'000'000;  // 10 Hz

DegeneracyLabel Label(int k, bool degenerate, const Eigen::Vector3d& dir, TimeNs jitter = 0) {
  return {kT0 + k * kPeriod + jitter, degenerate, dir};
}

// x rotated by `deg` about z.
Eigen::Vector3d Tilted(double deg) {
  return Eigen::AngleAxisd(deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d::UnitX();
}

TEST(DegeneracyScore, ConfusionCountsAnglesAndUnmatchedScans) {
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY();
  // Truth: scans 0-5 degenerate along x, 6-9 not.
  std::vector<DegeneracyLabel> truth;
  for (int k = 0; k < 10; ++k) truth.push_back(Label(k, k < 6, x));
  // Detection (2 ms late): flags 0-3 (TP, directions tilted by 10, 20, 30
  // degrees and a flipped sign), misses 4-5 (FN), flags 6 (FP), skips 9 (no row).
  std::vector<DegeneracyLabel> detected = {
      Label(0, true, Tilted(10), 2'000'000),  Label(1, true, Tilted(20), 2'000'000),
      Label(2, true, -Tilted(30), 2'000'000), Label(3, true, Eigen::Vector3d::Zero(), 2'000'000),
      Label(4, false, y, 2'000'000),          Label(5, false, y, 2'000'000),
      Label(6, true, y, 2'000'000),           Label(7, false, y, 2'000'000),
      Label(8, false, y, 2'000'000)};
  StatusOr<DegeneracyScores> s = ScoreDegeneracy(truth, detected, 0.01);
  ASSERT_TRUE(s.ok()) << s.status().message();
  EXPECT_EQ(s->matched, 9u);
  EXPECT_EQ(s->true_positive, 4u);
  EXPECT_EQ(s->false_negative, 2u);
  EXPECT_EQ(s->false_positive, 1u);
  EXPECT_EQ(s->true_negative, 2u);
  EXPECT_DOUBLE_EQ(s->precision, 4.0 / 5.0);
  EXPECT_DOUBLE_EQ(s->recall, 4.0 / 6.0);
  // Scan 3 flags no direction: three angles, sign-free.
  EXPECT_EQ(s->angle_deg.count, 3u);
  EXPECT_NEAR(s->angle_deg.mean, 20.0, 1e-9);
  EXPECT_NEAR(s->angle_deg.median, 20.0, 1e-9);
  EXPECT_NEAR(s->angle_deg.max, 30.0, 1e-9);
}

TEST(DegeneracyScore, UndefinedRatesAreNaN) {
  std::vector<DegeneracyLabel> truth, detected;
  for (int k = 0; k < 4; ++k) {
    truth.push_back(Label(k, false, Eigen::Vector3d::UnitZ()));
    detected.push_back(Label(k, false, Eigen::Vector3d::Zero()));
  }
  StatusOr<DegeneracyScores> s = ScoreDegeneracy(truth, detected, 0.01);
  ASSERT_TRUE(s.ok());
  EXPECT_TRUE(std::isnan(s->precision));
  EXPECT_TRUE(std::isnan(s->recall));
  EXPECT_EQ(s->angle_deg.count, 0u);
  EXPECT_TRUE(std::isnan(s->angle_deg.mean));
  EXPECT_EQ(s->true_negative, 4u);
}

TEST(DegeneracyScore, AxisAngleIsSignFree) {
  EXPECT_NEAR(AxisAngleDeg(Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX()), 0.0, 1e-9);
  EXPECT_NEAR(AxisAngleDeg(Eigen::Vector3d::UnitX(), Eigen::Vector3d(1, 1, 0)), 45.0, 1e-9);
  EXPECT_NEAR(AxisAngleDeg(Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()), 90.0, 1e-9);
}

// Straight flight along x at 1 m/s; the estimate drifts 2 cm per metre along
// x (the weak direction) and 5 mm sideways (well constrained): with no
// alignment the error along the weak direction is the drift alone.
TEST(DegeneracyScore, ErrorAlongTheTrueWeakDirection) {
  std::vector<DegeneracyLabel> truth, detected;
  Trajectory gt, est;
  for (int k = 0; k <= 100; ++k) {
    const double x = 0.1 * k;
    truth.push_back(Label(k, k >= 50, Eigen::Vector3d::UnitX()));
    detected.push_back(Label(k, k >= 50, Eigen::Vector3d::UnitX()));
    StampedPose g, e;
    g.t_ns = e.t_ns = kT0 + k * kPeriod;
    g.p_world_imu = Eigen::Vector3d(x, 0, 0);
    e.p_world_imu = Eigen::Vector3d(1.02 * x, 0.005, 0);
    gt.push_back(g);
    est.push_back(e);
  }
  EvalOptions options;
  options.align = "none";
  StatusOr<DegeneracyScores> s = ScoreDegeneracy(truth, detected, gt, est, options);
  ASSERT_TRUE(s.ok()) << s.status().message();
  EXPECT_EQ(s->error_scans, 101u);
  EXPECT_NEAR(s->path_length_m, 10.0, 1e-9);
  EXPECT_NEAR(s->along_weak_final_m, 0.2, 1e-9);
  EXPECT_NEAR(s->along_weak_growth_per_100m, 2.0, 1e-9);
  double sum2 = 0.0;
  for (int k = 0; k <= 100; ++k) sum2 += std::pow(0.002 * k, 2);
  EXPECT_NEAR(s->along_weak_rms_m, std::sqrt(sum2 / 101), 1e-9);
  double sum2_degenerate = 0.0;
  for (int k = 50; k <= 100; ++k) sum2_degenerate += std::pow(0.002 * k, 2);
  EXPECT_NEAR(s->along_weak_rms_degenerate_m, std::sqrt(sum2_degenerate / 51), 1e-9);
}

TEST(DegeneracyScore, BadInputIsAnError) {
  std::vector<DegeneracyLabel> truth = {Label(0, true, Eigen::Vector3d::UnitX())};
  std::vector<DegeneracyLabel> far = {Label(0, true, Eigen::Vector3d::UnitX(), 500'000'000)};
  EXPECT_FALSE(ScoreDegeneracy(truth, far, 0.01).ok());  // no scan within max_dt
  EXPECT_FALSE(ScoreDegeneracy(truth, {}, 0.01).ok());
  std::vector<DegeneracyLabel> not_unit = {Label(0, true, Eigen::Vector3d(2, 0, 0))};
  StatusOr<DegeneracyScores> s = ScoreDegeneracy(not_unit, truth, 0.01);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.status().code(), StatusCode::kInvalidInput);
}

}  // namespace
}  // namespace rvlio

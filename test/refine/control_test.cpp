// Survey ties (refine/control.h): the yaw-and-translation alignment and its
// refusals, attachment of a tie time to the states, square-root
// information, wall-target sightings, and ties pulling a refinement problem.
#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include "rvlio/factors/manifolds.h"
#include "rvlio/refine/control.h"
#include "rvlio/refine/chunks.h"

namespace rvlio {
namespace {

Pose3 YawPose(double yaw_deg, const Eigen::Vector3d& t) {
  return Pose3(Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix(), t);
}

TEST(FitYawTranslation, RecoversYawAndTranslationOfSurveySizedFrames) {
  const Pose3 truth = YawPose(30.0, Eigen::Vector3d(500000.0, 5400000.0, 250.0));
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.002);
  std::vector<AlignmentPoint> points;
  for (double x : {0.0, 50.0, 100.0, 150.0, 200.0}) {
    const Eigen::Vector3d p(x, 0.1 * x, -0.3);
    points.push_back({p, truth * p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)), 1.0});
  }
  StatusOr<YawTranslation> fit = FitYawTranslation(points, 1.0);
  ASSERT_TRUE(fit.ok()) << fit.status().message();
  EXPECT_NEAR(fit->yaw_deg, 30.0, 1e-3);
  EXPECT_LT((fit->T_survey_frame.t - truth.t).norm(), 0.01);
  for (const AlignmentPoint& q : points)
    EXPECT_LT((fit->T_survey_frame * q.p_frame - q.p_survey).norm(), 0.01);
  EXPECT_NEAR(fit->spread_m, std::hypot(200.0, 20.0), 0.01);
}

TEST(FitYawTranslation, TwoPointsFixTheFrameAndWeightsCount) {
  const Pose3 truth = YawPose(-100.0, Eigen::Vector3d(10.0, -4.0, 2.0));
  std::vector<AlignmentPoint> points = {{Eigen::Vector3d(0, 0, 0), truth * Eigen::Vector3d(0, 0, 0), 1.0},
                                        {Eigen::Vector3d(5, 0, 1), truth * Eigen::Vector3d(5, 0, 1), 1.0}};
  StatusOr<YawTranslation> fit = FitYawTranslation(points, 1.0);
  ASSERT_TRUE(fit.ok());
  EXPECT_NEAR(fit->yaw_deg, -100.0, 1e-9);
  // A third, wrong point with a tiny weight barely moves the fit.
  points.push_back({Eigen::Vector3d(10, 0, 0), truth * Eigen::Vector3d(10, 0, 0) + Eigen::Vector3d(1, 0, 0), 1e-9});
  fit = FitYawTranslation(points, 1.0);
  ASSERT_TRUE(fit.ok());
  EXPECT_NEAR(fit->yaw_deg, -100.0, 1e-6);
}

TEST(FitYawTranslation, RefusesPointsThatCannotFixTheHeading) {
  const Eigen::Vector3d p(500000.0, 5400000.0, 200.0);
  // One point.
  StatusOr<YawTranslation> fit = FitYawTranslation({{Eigen::Vector3d::Zero(), p, 1.0}}, 1.0);
  ASSERT_FALSE(fit.ok());
  EXPECT_NE(fit.status().message().find("cannot fix the heading"), std::string::npos);
  // Three marks at one place (stacked vertically: no horizontal extent).
  fit = FitYawTranslation({{Eigen::Vector3d(0, 0, 0), p, 1.0},
                           {Eigen::Vector3d(0.1, 0, 1), p + Eigen::Vector3d(0.1, 0, 1), 1.0},
                           {Eigen::Vector3d(0, 0.2, 2), p + Eigen::Vector3d(0, 0.2, 2), 1.0}},
                          1.0);
  ASSERT_FALSE(fit.ok());
  EXPECT_NE(fit.status().message().find("control.min_spread_m"), std::string::npos);
}

TEST(AttachTie, BetweenTwoStatesOrOnOne) {
  std::vector<RefineState> states(3);
  states[0].t_ns = 100;
  states[1].t_ns = 200;
  states[2].t_ns = 400;
  EXPECT_EQ(AttachTie(states, 99).k, -1);
  EXPECT_EQ(AttachTie(states, 401).k, -1);
  TieAttachment a = AttachTie(states, 200);
  EXPECT_EQ(a.k, 1);
  EXPECT_FALSE(a.two_states);
  a = AttachTie(states, 250);
  EXPECT_EQ(a.k, 1);
  EXPECT_TRUE(a.two_states);
  EXPECT_DOUBLE_EQ(a.alpha, 0.25);
  a = AttachTie(states, 100);
  EXPECT_EQ(a.k, 0);
  EXPECT_FALSE(a.two_states);
}

TEST(SqrtInformation, WhitensTheCovariance) {
  Eigen::Matrix3d cov;
  cov << 4e-4, 1e-4, 0, 1e-4, 9e-4, 0, 0, 0, 2.5e-3;
  Eigen::Matrix3d W;
  ASSERT_TRUE(SqrtInformationOf(cov, &W));
  EXPECT_TRUE((W * cov * W.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-9));
  EXPECT_FALSE(SqrtInformationOf(Eigen::Matrix3d::Zero(), &W));
  EXPECT_TRUE(IsotropicSqrtInformation(0.01).isApprox(Eigen::Matrix3d::Identity() * 100.0));
}

TEST(TargetSightings, KeepsTheClosestScansWithinTheRadius) {
  const Eigen::Vector3d target(10.0, 5.0, 2.0);
  TargetSightings sightings({target}, 0.3, 2);
  const Pose3 T_imu_lidar(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 0.1));
  for (int k = 0; k < 4; ++k) {
    const Pose3 T_world_imu = YawPose(10.0 * k, Eigen::Vector3d(k, 0, 0));
    const Eigen::Vector3d near = target + Eigen::Vector3d(0.05 * (k + 1), 0, 0);  // 5, 10, 15, 20 cm
    Scan scan;
    scan.t_end_ns = 1000 * (k + 1);
    LidarPoint p;
    p.p_lidar = ((T_world_imu * T_imu_lidar).Inverse() * near).cast<float>();
    scan.points.push_back(p);
    p.p_lidar = Eigen::Vector3f(1, 1, 1);
    scan.points.push_back(p);
    sightings.AddScan(scan, T_world_imu, T_imu_lidar);
  }
  Scan far;  // no point near: not a sighting
  far.t_end_ns = 9000;
  LidarPoint p;
  far.points.push_back(p);
  sightings.AddScan(far, Pose3(), T_imu_lidar);
  const std::vector<TargetSighting>& s = sightings.sightings()[0];
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].t_ns, 1000);
  EXPECT_EQ(s[1].t_ns, 2000);
  EXPECT_NEAR(s[0].distance_m, 0.05, 1e-5);
  // The target carried back by that scan's pose is the target.
  EXPECT_LT((YawPose(0.0, Eigen::Vector3d(0, 0, 0)) * s[0].p_imu_point - target).norm(), 1e-9);
}

TEST(PositionTies, PullFreePosesOntoTheMarksInTheirChunkOnly) {
  // Two states, free poses at the origin; a tie on each pulls it to its mark
  // (at the IMU origin: with a lever arm the rotation would share the step).
  // A chunk holding only state 0 takes only the first tie.
  std::vector<RefineState> states(2);
  for (int k = 0; k < 2; ++k) {
    states[k].t_ns = 1000 * (k + 1);
    PoseBlock().ToArray(states[k].pose.data());
  }
  std::vector<PositionTie> ties(2);
  for (int k = 0; k < 2; ++k) {
    ties[k].t_ns = states[k].t_ns;
    ties[k].p_imu_point = Eigen::Vector3d::Zero();
    ties[k].p_world = Eigen::Vector3d(5.0 * k, 1.0, 0.0);
    ties[k].sqrt_information = IsotropicSqrtInformation(0.005);
    ties[k].kernel = TieKernel::kHuber;
  }
  EXPECT_TRUE(RangeHoldsTie(ties, ScanRange{0, 1}, states));
  EXPECT_FALSE(RangeHoldsTie(ties, ScanRange{0, 0}, states));
  PoseManifold manifold;
  ceres::Problem::Options po;
  po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  for (RefineState& s : states) problem.AddParameterBlock(s.pose.data(), 7, &manifold);
  EXPECT_EQ(AddRefinePositionTies(ties, ScanRange{0, 1}, &states, &problem), 1);
  ceres::Solver::Options so;
  so.max_num_iterations = 50;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  EXPECT_LT((states[0].T_world_imu().t - Eigen::Vector3d(0, 1.0, 0.0)).norm(), 1e-6);
  EXPECT_LT(states[1].T_world_imu().t.norm(), 1e-12);  // its tie was not in the chunk
}



TEST(FitYawTranslation, RefinesATiltThePointsFixAndKeepsGravitysWhereTheyDoNot) {
  // The frame is tilted by 0.25 deg in pitch (an accelerometer bias read as
  // gravity): marks along x at one height in the survey frame.
  const double pitch = 0.25 * M_PI / 180.0;
  const Pose3 truth(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                        Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()).toRotationMatrix(),
                    Eigen::Vector3d(500000.0, 5400000.0, 250.0));
  std::vector<AlignmentPoint> points;
  for (double x : {0.0, 10.0, 20.0, 30.0}) {
    const Eigen::Vector3d p_survey = truth * Eigen::Vector3d(x, 0.0, 0.0);
    points.push_back({truth.Inverse() * p_survey, p_survey, 1.0 / (0.005 * 0.005)});
  }
  StatusOr<YawTranslation> yaw_only = FitYawTranslation(points, 1.0);
  StatusOr<YawTranslation> tilted = FitYawTranslation(points, 1.0, 0.5 * M_PI / 180.0);
  ASSERT_TRUE(yaw_only.ok() && tilted.ok());
  double worst_yaw_only = 0.0, worst_tilted = 0.0;
  for (const AlignmentPoint& q : points) {
    worst_yaw_only = std::max(worst_yaw_only, (yaw_only->T_survey_frame * q.p_frame - q.p_survey).norm());
    worst_tilted = std::max(worst_tilted, (tilted->T_survey_frame * q.p_frame - q.p_survey).norm());
  }
  EXPECT_GT(worst_yaw_only, 0.05);  // 13 cm of height over 30 m, split
  EXPECT_LT(worst_tilted, 0.002);
  EXPECT_NEAR(tilted->tilt_deg[1], 0.25, 0.01);
  // The roll about the line of marks is not fixed by them: the prior keeps it at 0.
  EXPECT_NEAR(tilted->tilt_deg[0], 0.0, 1e-6);
}



TEST(TieKernelWeight, HuberCauchyNone) {
  EXPECT_DOUBLE_EQ(TieKernelWeight(TieKernel::kHuber, 3.0, 2.0), 1.0);
  EXPECT_DOUBLE_EQ(TieKernelWeight(TieKernel::kHuber, 3.0, 6.0), 0.5);
  EXPECT_DOUBLE_EQ(TieKernelWeight(TieKernel::kCauchy, 2.0, 2.0), 0.5);
  EXPECT_DOUBLE_EQ(TieKernelWeight(TieKernel::kNone, 2.0, 100.0), 1.0);
}

}  // namespace
}  // namespace rvlio

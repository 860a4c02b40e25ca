// SurveyTies (api/survey_ties.h) on synthetic inputs: the robust alignment
// of GNSS fixes with multipath outliers, the local frame, and the residuals.
#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "rvlio/api/survey_ties.h"

namespace rvlio {
namespace {

// A straight flight along x at 1.5 m/s, 10 Hz, in rvlio's world frame.
Trajectory StraightFlight(double length_m) {
  Trajectory t;
  for (int k = 0; k * 0.15 <= length_m; ++k)
    t.push_back({1700000000000000000 + k * 100000000LL, Eigen::Vector3d(k * 0.15, 0.0, 1.5),
                 Eigen::Quaterniond::Identity()});
  return t;
}

TEST(SurveyTies, GnssAlignmentShrugsOffMultipathOutliers) {
  const Pose3 T_survey_world(
      Eigen::AngleAxisd(30.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
      Eigen::Vector3d(500000.0, 5400000.0, 250.0));
  const Trajectory flight = StraightFlight(80.0);
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 0.015);
  std::vector<SurveyFix> fixes;
  for (size_t k = 0; k < flight.size(); k += 2) {
    const double x = flight[k].p_world_imu.x();
    if (x > 10.0 && x < 70.0) continue;  // inside the tunnel: no fix
    SurveyFix f;
    f.t_ns = flight[k].t_ns;
    f.p_survey = T_survey_world * flight[k].p_world_imu +
                 Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    if (fixes.size() == 5 || fixes.size() == 40) f.p_survey += Eigen::Vector3d(2.1, 2.1, 0.0);
    f.sigma_m = 0.015;
    f.sqrt_information = IsotropicSqrtInformation(0.015);
    fixes.push_back(f);
  }
  Configuration options;
  SurveyTies ties("", {}, fixes, options);
  Trajectory init = flight;
  SurveyFactors out;
  LocalOrigin origin;
  ASSERT_TRUE(ties.Prepare(false, &origin, &init, &out).ok());
  EXPECT_EQ(out.ties.size(), fixes.size());
  EXPECT_TRUE(out.rests.empty());
  // The initial trajectory in the local survey frame: within 1 cm of the truth.
  for (size_t k = 0; k < init.size(); ++k)
    EXPECT_LT((ties.origin().ToUser(init[k].p_world_imu) - T_survey_world * flight[k].p_world_imu).norm(),
              0.01)
        << k;
  EXPECT_EQ(origin.t_user_local, Eigen::Vector3d(500000.0, 5400000.0, 0.0));
  const nlohmann::json j = ties.SurveyJson("EPSG:25832");
  EXPECT_NEAR(j["alignment"]["yaw_deg"].get<double>(), 30.0, 0.02);
  EXPECT_EQ(j["gnss_fixes"], fixes.size());
}

TEST(SurveyTies, ResidualsOfMarksAtTheRefinedTrajectory) {
  const Trajectory flight = StraightFlight(30.0);
  std::vector<ControlRow> rows(3);
  for (int i = 0; i < 3; ++i) {
    rows[i].line = i + 2;
    rows[i].name = "M" + std::to_string(i + 1);
    rows[i].has_times = true;
    rows[i].t_start_ns = flight[i * 100].t_ns;  // 15 m apart, at the 0.3 m-high IMU
    rows[i].t_end_ns = flight[i * 100].t_ns;
    rows[i].p_survey = flight[i * 100].p_world_imu - Eigen::Vector3d(0, 0, 0.3);
  }
  rows[1].role = ControlRole::kCheck;
  rows[1].p_survey.x() += 0.004;  // the check point's given coordinates are 4 mm off
  Configuration options;
  options.control.lever_arm = {0.0, 0.0, 0.3};
  SurveyTies ties("marks.csv", rows, {}, options);
  Trajectory init = flight;
  SurveyFactors out;
  LocalOrigin origin;
  ASSERT_TRUE(ties.Prepare(false, &origin, &init, &out).ok());
  EXPECT_EQ(out.ties.size(), 2u);  // the check point does not enter the solve
  EXPECT_EQ(out.rests.size(), 3u);  // every mark's rest
  ties.Evaluate(init);
  const std::vector<ControlResidual>& r = ties.residuals();
  ASSERT_EQ(r.size(), 3u);
  EXPECT_LT(r[0].Residual().norm(), 1e-3);
  EXPECT_NEAR(r[1].Residual().x(), -0.004 + (r[0].Residual().x() + r[2].Residual().x()) / 2, 2e-3);
  const std::string csv = ties.ControlCsv();
  EXPECT_NE(csv.find("M2,check,mark,"), std::string::npos) << csv;
  EXPECT_EQ(ties.ControlJson()["check"]["count"], 1);
}

}  // namespace
}  // namespace rvlio

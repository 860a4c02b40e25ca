#include "rvlio/sim/marks.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "rvlio/sim/random.h"

namespace rvlio::sim {
namespace {

constexpr uint64_t kMarksStream = 11;
constexpr uint64_t kGnssStream = 12;
constexpr double kMinMarkRestS = 1.0;

Eigen::Vector3d Noise(Rng& rng, double horizontal, double vertical) {
  const double x = rng.Normal(horizontal), y = rng.Normal(horizontal), z = rng.Normal(vertical);
  return {x, y, z};
}

}  // namespace

Pose3 SurveyFromWorld(const SimMarksOptions& marks) {
  const auto& f = marks.survey_frame;
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(f[3] * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return Pose3(R, Eigen::Vector3d(f[0], f[1], f[2]));
}

std::vector<SimMark> SimulateMarks(const Simulator& simulator) {
  const SimOptions& o = simulator.options();
  const FlightTrajectory& flight = simulator.trajectory();
  const Pose3 T_survey_world = SurveyFromWorld(o.marks);
  Rng rng = Rng::Stream(o.FlightSeed(), kMarksStream);
  std::vector<SimMark> out;
  for (const auto& [begin_s, end_s] : flight.landed()) {
    const TimeNs t0 = flight.t0_ns() + SecondsToNs(begin_s);
    const TimeNs t1 = std::min(simulator.end_time_ns(), flight.t0_ns() + SecondsToNs(std::min(end_s, 1e9)));
    if (NsToSeconds(t1 - t0) < kMinMarkRestS) continue;
    SimMark m;
    m.name = "M" + std::to_string(out.size() + 1);
    m.check = o.marks.check_every > 0 && (out.size() + 1) % o.marks.check_every == 0;
    const Eigen::Vector3d p_imu = flight.At(t0 + (t1 - t0) / 2).T_world_imu.t;
    const Eigen::Vector3d floor = p_imu - Eigen::Vector3d(0.0, 0.0, o.world.start_height);
    m.p_survey_true = T_survey_world * floor;
    m.p_survey = m.p_survey_true + Noise(rng, o.marks.noise_m, o.marks.noise_m);
    m.t_start_ns = t0;
    m.t_end_ns = t1;
    out.push_back(m);
  }
  return out;
}

std::vector<SimFix> SimulateFixes(const Simulator& simulator) {
  const SimOptions& o = simulator.options();
  const SimGnssOptions& g = o.gnss;
  const WorldLayout& L = simulator.layout();
  const Pose3 T_survey_world = SurveyFromWorld(o.marks);
  const Eigen::Vector3d lever(g.lever_arm[0], g.lever_arm[1], g.lever_arm[2]);
  Rng rng = Rng::Stream(o.FlightSeed(), kGnssStream);
  std::vector<SimFix> out;
  const double step_ns = 1e9 / g.rate;
  for (int64_t k = 0;; ++k) {
    const TimeNs t = simulator.start_time_ns() + static_cast<TimeNs>(std::llround(k * step_ns));
    if (t > simulator.end_time_ns()) break;
    // Every draw is made for every epoch, so that a change of the geometry
    // leaves the noise of the other fixes as it was.
    const Eigen::Vector3d noise = Noise(rng, g.noise_m, g.noise_vertical_m);
    const double drop = rng.Uniform(), multipath = rng.Uniform(), angle = rng.Uniform(0.0, 2 * M_PI);
    const Eigen::Vector3d p_world = simulator.TruthAt(t).T_world_imu * lever;
    const bool before = p_world.x() < L.x_entrance - g.portal_margin_m;
    const bool after = !o.world.end_wall && p_world.x() > L.x_end + g.portal_margin_m;
    if (!(before || after) || drop < g.dropout) continue;
    SimFix f;
    f.t_ns = t;
    f.outlier = multipath < g.outlier_rate;
    f.p_survey = T_survey_world * p_world + noise;
    if (f.outlier) f.p_survey += g.outlier_m * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
    out.push_back(f);
  }
  return out;
}

}  // namespace rvlio::sim

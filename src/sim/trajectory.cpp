#include "rvlio/sim/trajectory.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "rvlio/common/check.h"
#include "rvlio/math/so3.h"
#include "rvlio/sim/random.h"

namespace rvlio::sim {

namespace {

constexpr double kYawEnvelope = 2.0;          // s over which the yaw motion fades in
constexpr double kYawFreq[2] = {0.05, 0.13};  // Hz
constexpr double kYawWeight[2] = {0.7, 0.3};
constexpr double kSwayFreqRatio[3] = {1.0, 1.37, 0.71};  // roll, pitch, yaw

// Septic smoothstep and its derivatives / integral on [0, 1].
double S(double x) { return x * x * x * x * (35.0 + x * (-84.0 + x * (70.0 - 20.0 * x))); }
double S1(double x) {
  const double y = x * (1.0 - x);
  return 140.0 * y * y * y;
}
double S2(double x) {
  const double y = x * (1.0 - x);
  return 420.0 * y * y * (1.0 - 2.0 * x);
}
double SInt(double x) { return x * x * x * x * x * (7.0 + x * (-14.0 + x * (10.0 - 2.5 * x))); }

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\n\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\n\r") - a + 1);
}

Eigen::Vector3d Cross(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return a.cross(b); }

}  // namespace

StatusOr<std::vector<Eigen::Vector3d>> ParseWaypoints(const std::string& text) {
  std::vector<Eigen::Vector3d> out;
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ';')) {
    item = Trim(item);
    if (item.empty()) continue;
    std::stringstream coords(item);
    std::string c;
    std::vector<double> values;
    while (std::getline(coords, c, ',')) {
      c = Trim(c);
      char* end = nullptr;
      const double x = std::strtod(c.c_str(), &end);
      if (c.empty() || end != c.c_str() + c.size() || !std::isfinite(x))
        return Status::InvalidInput("trajectory.waypoints: '" + item + "' is not x,y,z");
      values.push_back(x);
    }
    if (values.size() != 3)
      return Status::InvalidInput("trajectory.waypoints: '" + item + "' is not x,y,z");
    out.emplace_back(values[0], values[1], values[2]);
  }
  if (out.empty()) return Status::InvalidInput("trajectory.waypoints: no waypoint given");
  return out;
}

FlightTrajectory::FlightTrajectory(std::vector<Eigen::Vector3d> waypoints,
                                   const SimTrajectoryOptions& options, double gravity,
                                   TimeNs t0_ns, uint64_t seed)
    : waypoints_(std::move(waypoints)), options_(options), gravity_(gravity), t0_ns_(t0_ns) {
  RVLIO_CHECK(!waypoints_.empty());
  double t = options.static_duration;
  arrival_s_.push_back(0.0);
  landed_s_.push_back({0.0, options.static_duration});
  for (size_t i = 0; i + 1 < waypoints_.size(); ++i) {
    Segment s;
    const Eigen::Vector3d delta = waypoints_[i + 1] - waypoints_[i];
    s.t_begin = t;
    s.from = waypoints_[i];
    s.length = delta.norm();
    if (s.length > 0.0) s.dir = delta / s.length;
    const bool horizontal = delta.head<2>().norm() >= std::abs(delta.z());
    s.speed = horizontal ? options.cruise_speed : options.climb_speed;
    s.ramp = options.ramp_time;
    // Each ramp covers speed * ramp / 2 (the mean of S is 1/2); a short
    // segment lowers the speed instead of the ramp time.
    if (s.length < s.speed * s.ramp) s.speed = s.length / s.ramp;
    s.cruise = s.speed > 0.0 ? s.length / s.speed - s.ramp : 0.0;
    s.cruise = std::max(0.0, s.cruise);
    segments_.push_back(s);
    arrival_s_.push_back(s.t_end());
    const bool landing = options.landing_time > 0.0 && waypoints_[i + 1].z() <= 0.0;
    const double rest = landing ? options.landing_time : options.hover_time;
    const bool last = i + 2 == waypoints_.size();
    if (landing) landed_s_.push_back({s.t_end(), last ? 1e300 : s.t_end() + rest});
    t = s.t_end() + rest;
  }
  Rng rng = Rng::Stream(seed, 7);
  for (double& phase : yaw_phase_) phase = rng.Uniform(0.0, 2.0 * M_PI);
  Rng sway_rng = Rng::Stream(seed, 8);  // own stream: no sway leaves every other draw as it was
  for (double& phase : sway_phase_) phase = sway_rng.Uniform(0.0, 2.0 * M_PI);
}

void FlightTrajectory::AlongSegment(const Segment& s, double tau, double* d, double* v, double* a,
                                    double* j) const {
  const double local = tau - s.t_begin, V = s.speed, r = s.ramp;
  const double total = 2.0 * r + s.cruise;
  if (local < r) {
    const double x = local / r;
    *d = V * r * SInt(x);
    *v = V * S(x);
    *a = V * S1(x) / r;
    *j = V * S2(x) / (r * r);
  } else if (local < r + s.cruise) {
    *d = 0.5 * V * r + V * (local - r);
    *v = V;
    *a = 0.0;
    *j = 0.0;
  } else {
    const double x = std::max(0.0, (total - local) / r);
    *d = s.length - V * r * SInt(x);
    *v = V * S(x);
    *a = -V * S1(x) / r;
    *j = V * S2(x) / (r * r);
  }
}

void FlightTrajectory::Translation(double tau, Eigen::Vector3d* p, Eigen::Vector3d* v,
                                   Eigen::Vector3d* a, Eigen::Vector3d* jerk) const {
  Eigen::Vector3d rest = waypoints_.front();
  for (size_t i = 0; i < segments_.size(); ++i) {
    const Segment& s = segments_[i];
    if (tau < s.t_begin) break;
    if (tau < s.t_end()) {
      double d = 0, sv = 0, sa = 0, sj = 0;
      AlongSegment(s, tau, &d, &sv, &sa, &sj);
      *p = s.from + d * s.dir;
      *v = sv * s.dir;
      *a = sa * s.dir;
      *jerk = sj * s.dir;
      return;
    }
    rest = waypoints_[i + 1];
  }
  *p = rest;
  v->setZero();
  a->setZero();
  jerk->setZero();
}

void FlightTrajectory::Yaw(double tau, double* yaw, double* yaw_rate) const {
  const double s = tau - options_.static_duration;
  *yaw = 0.0;
  *yaw_rate = 0.0;
  if (s <= 0.0 || options_.yaw_amplitude == 0.0) return;
  const double x = std::min(1.0, s / kYawEnvelope);
  const double env = S(x), env_rate = x < 1.0 ? S1(x) / kYawEnvelope : 0.0;
  double y = 0.0, y_rate = 0.0;
  for (int k = 0; k < 2; ++k) {
    const double w = 2.0 * M_PI * kYawFreq[k];
    y += kYawWeight[k] * std::sin(w * s + yaw_phase_[k]);
    y_rate += kYawWeight[k] * w * std::cos(w * s + yaw_phase_[k]);
  }
  *yaw = options_.yaw_amplitude * env * y;
  *yaw_rate = options_.yaw_amplitude * (env_rate * y + env * y_rate);
}

void FlightTrajectory::Sway(double tau, Eigen::Vector3d* phi, Eigen::Vector3d* phi_rate) const {
  const double s = tau - options_.static_duration;
  phi->setZero();
  phi_rate->setZero();
  if (s <= 0.0 || options_.sway_amplitude == 0.0) return;
  const double x = std::min(1.0, s / kYawEnvelope);
  const double env = S(x), env_rate = x < 1.0 ? S1(x) / kYawEnvelope : 0.0;
  for (int i = 0; i < 3; ++i) {
    const double w = 2.0 * M_PI * options_.sway_frequency * kSwayFreqRatio[i];
    const double y = std::sin(w * s + sway_phase_[i]), y_rate = w * std::cos(w * s + sway_phase_[i]);
    (*phi)[i] = options_.sway_amplitude * env * y;
    (*phi_rate)[i] = options_.sway_amplitude * (env_rate * y + env * y_rate);
  }
}

// Attitude from the required thrust: z_b = f / |f| with f = a - g_world, y_b
// = normalize(z_b x x_c) with the heading x_c = (cos yaw, sin yaw, 0), x_b =
// y_b x z_b. The angular rate is vee(R^T dR/dt) with dR/dt from the exact
// derivatives of these unit vectors (f' = jerk).
TruthState FlightTrajectory::At(TimeNs t_ns) const {
  const double tau = std::max(0.0, NsToSeconds(t_ns - t0_ns_));
  TruthState s;
  s.t_ns = t_ns;
  Eigen::Vector3d p, v, a, j;
  Translation(tau, &p, &v, &a, &j);
  double yaw = 0.0, yaw_rate = 0.0;
  Yaw(tau, &yaw, &yaw_rate);

  const Eigen::Vector3d f = a + Eigen::Vector3d(0.0, 0.0, gravity_);
  const double fn = f.norm();
  const Eigen::Vector3d z = f / fn;
  const Eigen::Vector3d z_dot = (j - z * z.dot(j)) / fn;
  const Eigen::Vector3d xc(std::cos(yaw), std::sin(yaw), 0.0);
  const Eigen::Vector3d xc_dot = yaw_rate * Eigen::Vector3d(-std::sin(yaw), std::cos(yaw), 0.0);
  const Eigen::Vector3d m = Cross(z, xc);
  const double mn = m.norm();
  const Eigen::Vector3d y = m / mn;
  const Eigen::Vector3d m_dot = Cross(z_dot, xc) + Cross(z, xc_dot);
  const Eigen::Vector3d y_dot = (m_dot - y * y.dot(m_dot)) / mn;
  const Eigen::Vector3d x = Cross(y, z);
  const Eigen::Vector3d x_dot = Cross(y_dot, z) + Cross(y, z_dot);

  Eigen::Matrix3d R, R_dot;
  R << x, y, z;
  R_dot << x_dot, y_dot, z_dot;
  const Eigen::Matrix3d W = R.transpose() * R_dot;  // = Hat(w_imu)
  s.T_world_imu = Pose3(R, p);
  s.v_world_imu = v;
  s.a_world_imu = a;
  s.w_imu = 0.5 * Eigen::Vector3d(W(2, 1) - W(1, 2), W(0, 2) - W(2, 0), W(1, 0) - W(0, 1));
  if (options_.sway_amplitude > 0.0) {
    // R' = R Exp(phi): w' = Exp(phi)^T w + Jr(phi) phi_dot.
    Eigen::Vector3d phi, phi_rate;
    Sway(tau, &phi, &phi_rate);
    const Eigen::Matrix3d R_sway = so3::Exp(phi);
    s.T_world_imu = Pose3(R * R_sway, p);
    s.w_imu = R_sway.transpose() * s.w_imu + so3::Jr(phi) * phi_rate;
  }
  return s;
}

bool FlightTrajectory::Landed(double tau) const {
  for (const auto& [begin, end] : landed_s_)
    if (tau >= begin && tau <= end) return true;
  return false;
}

std::vector<Eigen::Vector3d> FlightTrajectory::SamplePath(double step) const {
  RVLIO_CHECK(step > 0.0);
  std::vector<Eigen::Vector3d> out{waypoints_.front()};
  for (size_t i = 0; i + 1 < waypoints_.size(); ++i) {
    const Eigen::Vector3d delta = waypoints_[i + 1] - waypoints_[i];
    const int n = std::max(1, static_cast<int>(std::ceil(delta.norm() / step)));
    for (int k = 1; k <= n; ++k) out.push_back(waypoints_[i] + delta * (double(k) / n));
  }
  return out;
}

}  // namespace rvlio::sim

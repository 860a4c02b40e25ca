#include "rvlio/imu/integrator.h"

#include <algorithm>

#include "rvlio/common/check.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

bool IsSorted(const std::vector<ImuSample>& samples) {
  return std::is_sorted(samples.begin(), samples.end(),
                        [](const ImuSample& a, const ImuSample& b) { return a.t_ns < b.t_ns; });
}

// The signal at every knot of the integration from t0 to t1: t0, the samples
// strictly between them in the direction of travel, t1.
std::vector<ImuSample> Knots(const std::vector<ImuSample>& samples, TimeNs t0, TimeNs t1) {
  std::vector<ImuSample> knots{InterpolateImu(samples, t0)};
  const TimeNs lo = std::min(t0, t1);
  const TimeNs hi = std::max(t0, t1);
  for (const ImuSample& s : samples)
    if (s.t_ns > lo && s.t_ns < hi) knots.push_back(s);
  if (t1 < t0) std::reverse(knots.begin() + 1, knots.end());
  knots.push_back(InterpolateImu(samples, t1));
  return knots;
}

}  // namespace

ImuSample InterpolateImu(const std::vector<ImuSample>& samples, TimeNs t_ns) {
  RVLIO_CHECK(!samples.empty());
  ImuSample out;
  if (t_ns <= samples.front().t_ns) {
    out = samples.front();
  } else if (t_ns >= samples.back().t_ns) {
    out = samples.back();
  } else {
    const auto next = std::upper_bound(samples.begin(), samples.end(), t_ns,
                                       [](TimeNs t, const ImuSample& s) { return t < s.t_ns; });
    const ImuSample& a = *(next - 1);
    const ImuSample& b = *next;
    const double s = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
    out.acc_imu = (1.0 - s) * a.acc_imu + s * b.acc_imu;
    out.gyro_imu = (1.0 - s) * a.gyro_imu + s * b.gyro_imu;
  }
  out.t_ns = t_ns;
  return out;
}

ImuKinematics IntegrateInterval(const ImuKinematics& x, const ImuSample& m0, const ImuSample& m1,
                                const Eigen::Vector3d& bg, const Eigen::Vector3d& ba,
                                const Eigen::Vector3d& g_world) {
  const double h = NsToSeconds(m1.t_ns - x.t_ns);
  const Eigen::Vector3d omega = 0.5 * (m0.gyro_imu + m1.gyro_imu) - bg;
  ImuKinematics y;
  y.t_ns = m1.t_ns;
  y.R_world_imu = x.R_world_imu * so3::Exp(omega * h);
  const Eigen::Vector3d a_world =
      0.5 * (x.R_world_imu * (m0.acc_imu - ba) + y.R_world_imu * (m1.acc_imu - ba)) + g_world;
  y.p_world_imu = x.p_world_imu + x.v_world_imu * h + 0.5 * h * h * a_world;
  y.v_world_imu = x.v_world_imu + a_world * h;
  return y;
}

std::vector<ImuKinematics> IntegrateTrajectory(const ImuKinematics& start,
                                               const std::vector<ImuSample>& samples,
                                               TimeNs t_end_ns, const Eigen::Vector3d& bg,
                                               const Eigen::Vector3d& ba,
                                               const Eigen::Vector3d& g_world) {
  if (t_end_ns == start.t_ns) return {start};
  RVLIO_CHECK_MSG(IsSorted(samples), "IMU samples must be sorted by time");
  const std::vector<ImuSample> knots = Knots(samples, start.t_ns, t_end_ns);
  std::vector<ImuKinematics> states{start};
  states.reserve(knots.size());
  for (size_t i = 1; i < knots.size(); ++i)
    states.push_back(IntegrateInterval(states.back(), knots[i - 1], knots[i], bg, ba, g_world));
  return states;
}

ImuKinematics Integrate(const ImuKinematics& start, const std::vector<ImuSample>& samples,
                        TimeNs t_end_ns, const Eigen::Vector3d& bg, const Eigen::Vector3d& ba,
                        const Eigen::Vector3d& g_world) {
  return IntegrateTrajectory(start, samples, t_end_ns, bg, ba, g_world).back();
}

}  // namespace rvlio

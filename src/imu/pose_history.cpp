#include "rvlio/imu/pose_history.h"

#include <algorithm>

#include "rvlio/common/check.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

// Index of the latest sample with t <= t_ns (0 when t_ns precedes all).
size_t SampleIndexAt(const std::vector<ImuPoseSample>& samples, TimeNs t_ns) {
  auto it = std::upper_bound(samples.begin(), samples.end(), t_ns,
                             [](TimeNs t, const ImuPoseSample& s) { return t < s.t_ns; });
  return it == samples.begin() ? 0 : static_cast<size_t>(it - samples.begin()) - 1;
}

}  // namespace

Pose3 AdvanceImuPose(const ImuPoseSample& s, double dt_s) {
  return Pose3(s.R_world_imu * so3::Exp(s.gyro_imu * dt_s),
               s.p_world_imu + s.v_world_imu * dt_s + 0.5 * s.acc_world * dt_s * dt_s);
}

Pose3 InterpolateImuPose(const std::vector<ImuPoseSample>& samples, TimeNs t_ns) {
  RVLIO_CHECK(!samples.empty());
  const ImuPoseSample& s = samples[SampleIndexAt(samples, t_ns)];
  return AdvanceImuPose(s, NsToSeconds(t_ns - s.t_ns));
}

ImuPoseHistory ImuPoseHistory::Integrate(const ImuKinematics& start,
                                         const std::vector<ImuSample>& imu, TimeNs t_end_ns,
                                         const Eigen::Vector3d& bg, const Eigen::Vector3d& ba,
                                         const Eigen::Vector3d& g_world) {
  std::vector<ImuKinematics> knots = IntegrateTrajectory(start, imu, t_end_ns, bg, ba, g_world);
  if (t_end_ns < start.t_ns) std::reverse(knots.begin(), knots.end());
  std::vector<ImuSample> signal(knots.size());
  for (size_t i = 0; i < knots.size(); ++i) signal[i] = InterpolateImu(imu, knots[i].t_ns);
  ImuPoseHistory h;
  h.samples_.resize(knots.size());
  for (size_t i = 0; i < knots.size(); ++i) {
    const size_t j = i + 1 < knots.size() ? i + 1 : i;
    ImuPoseSample& s = h.samples_[i];
    s.t_ns = knots[i].t_ns;
    s.R_world_imu = knots[i].R_world_imu;
    s.p_world_imu = knots[i].p_world_imu;
    s.v_world_imu = knots[i].v_world_imu;
    s.gyro_imu = 0.5 * (signal[i].gyro_imu + signal[j].gyro_imu) - bg;
    s.acc_world = 0.5 * (knots[i].R_world_imu * (signal[i].acc_imu - ba) +
                         knots[j].R_world_imu * (signal[j].acc_imu - ba)) +
                  g_world;
  }
  return h;
}

void ImuPoseHistory::Append(const ImuPoseSample& sample) {
  RVLIO_CHECK(samples_.empty() || sample.t_ns >= samples_.back().t_ns);
  samples_.push_back(sample);
}

ImuKinematics ImuPoseHistory::Newest() const {
  RVLIO_CHECK(!samples_.empty());
  const ImuPoseSample& s = samples_.back();
  ImuKinematics x;
  x.t_ns = s.t_ns;
  x.R_world_imu = s.R_world_imu;
  x.p_world_imu = s.p_world_imu;
  x.v_world_imu = s.v_world_imu;
  return x;
}

}  // namespace rvlio

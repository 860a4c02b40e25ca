#include "rvlio/math/pose_interpolation.h"

#include <algorithm>

#include "rvlio/common/check.h"

namespace rvlio {

StampedPose InterpolateBetween(const StampedPose& a, const StampedPose& b, double w) {
  StampedPose out = a;
  out.p_world_imu = (1.0 - w) * a.p_world_imu + w * b.p_world_imu;
  out.q_world_imu = a.q_world_imu.normalized().slerp(w, b.q_world_imu.normalized());
  return out;
}

bool InterpolatePose(const Trajectory& trajectory, TimeNs t_ns, Pose3* T_world_imu) {
  RVLIO_CHECK(!trajectory.empty());
  if (t_ns < trajectory.front().t_ns || t_ns > trajectory.back().t_ns) return false;
  const auto hi = std::upper_bound(trajectory.begin(), trajectory.end(), t_ns,
                                   [](TimeNs t, const StampedPose& s) { return t < s.t_ns; });
  if (hi == trajectory.end()) {  // t_ns == back
    *T_world_imu = Pose3(trajectory.back().q_world_imu, trajectory.back().p_world_imu);
    return true;
  }
  const StampedPose& a = *(hi - 1);
  const StampedPose& b = *hi;
  const double w = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  const StampedPose between = InterpolateBetween(a, b, w);
  *T_world_imu = Pose3(between.q_world_imu, between.p_world_imu);
  return true;
}

}  // namespace rvlio

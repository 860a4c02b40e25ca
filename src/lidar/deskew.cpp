#include "rvlio/lidar/deskew.h"

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

// Constant angular rate and world acceleration over dt (may be negative).
Pose3 Advance(const ImuPoseSample& s, double dt_s) {
  return Pose3(s.R_world_imu * so3::Exp(s.gyro_imu * dt_s),
               s.p_world_imu + s.v_world_imu * dt_s + 0.5 * s.acc_world * dt_s * dt_s);
}

}  // namespace

Pose3 InterpolateImuPose(const std::vector<ImuPoseSample>& samples, TimeNs t_ns) {
  RVLIO_CHECK(!samples.empty());
  const ImuPoseSample& s = samples[SampleIndexAt(samples, t_ns)];
  return Advance(s, NsToSeconds(t_ns - s.t_ns));
}

void DeskewToScanEnd(const std::vector<ImuPoseSample>& samples, const Pose3& T_imu_lidar,
                     const std::vector<LidarPoint>& points, TimeNs t_end_ns,
                     std::vector<Eigen::Vector3d>* p_lidar_end) {
  RVLIO_CHECK(!samples.empty());
  const Pose3 T_lidarend_world = (InterpolateImuPose(samples, t_end_ns) * T_imu_lidar).Inverse();
  p_lidar_end->resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Pose3 T_world_lidar_i = InterpolateImuPose(samples, points[i].t_ns) * T_imu_lidar;
    (*p_lidar_end)[i] = T_lidarend_world * (T_world_lidar_i * points[i].p_lidar.cast<double>());
  }
}

}  // namespace rvlio

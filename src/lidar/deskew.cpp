#include "rvlio/lidar/deskew.h"

#include <algorithm>
#include <cstdint>

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
  // Spinning LiDARs stamp whole columns (Ouster: 1024 times for 32 x 1024
  // points), so the pose of a time is memoized in a small direct-mapped table
  // (the interpolation, a binary search and an SO(3) exponential, was ~8% of
  // a scan's instructions). The result is the same as without the table.
  constexpr int kMemoBits = 10;  // 1024 entries, indexed by a Fibonacci hash of the time
  struct Memo {
    TimeNs t_ns;
    bool valid;
    Pose3 T_world_lidar;
  };
  std::vector<Memo> memo(size_t{1} << kMemoBits, Memo{0, false, Pose3()});
  for (size_t i = 0; i < points.size(); ++i) {
    const TimeNs t = points[i].t_ns;
    Memo& m = memo[(static_cast<uint64_t>(t) * 0x9E3779B97F4A7C15ull) >> (64 - kMemoBits)];
    if (!m.valid || m.t_ns != t) m = Memo{t, true, InterpolateImuPose(samples, t) * T_imu_lidar};
    (*p_lidar_end)[i] = T_lidarend_world * (m.T_world_lidar * points[i].p_lidar.cast<double>());
  }
}

}  // namespace rvlio

#include "rvlio/lidar/deskew.h"

#include <algorithm>
#include <cstdint>

#include "rvlio/common/check.h"

namespace rvlio {

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

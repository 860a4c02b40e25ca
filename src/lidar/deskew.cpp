#include "rvlio/lidar/deskew.h"

#include <algorithm>
#include <cstdint>

#include "rvlio/common/check.h"

namespace rvlio {

namespace {

// n points, point i at time time(i) with coordinates p(i) (LiDAR frame).
template <class TimeOf, class PointOf>
void DeskewPoints(const std::vector<ImuPoseSample>& samples, const Pose3& T_imu_lidar, size_t n,
                  const TimeOf& time, const PointOf& p, TimeNs t_end_ns,
                  std::vector<Eigen::Vector3d>* p_lidar_end) {
  RVLIO_CHECK(!samples.empty());
  const Pose3 T_lidarend_world = (InterpolateImuPose(samples, t_end_ns) * T_imu_lidar).Inverse();
  p_lidar_end->resize(n);
  // Spinning LiDARs stamp whole columns (Ouster: 1024 times for 32 x 1024
  // points), so the pose of a time is memoized in a small direct-mapped table
  // (without it the interpolation per point, a binary search and an SO(3)
  // exponential, about doubles the deskew's instructions; bench/RESULTS.md).
  // The result is the same as without the table.
  constexpr int kMemoBits = 10;  // 1024 entries, indexed by a Fibonacci hash of the time
  struct Memo {
    TimeNs t_ns;
    bool valid;
    Pose3 T_world_lidar;
  };
  std::vector<Memo> memo(size_t{1} << kMemoBits, Memo{0, false, Pose3()});
  for (size_t i = 0; i < n; ++i) {
    const TimeNs t = time(i);
    Memo& m = memo[(static_cast<uint64_t>(t) * 0x9E3779B97F4A7C15ull) >> (64 - kMemoBits)];
    if (!m.valid || m.t_ns != t) m = Memo{t, true, InterpolateImuPose(samples, t) * T_imu_lidar};
    (*p_lidar_end)[i] = T_lidarend_world * (m.T_world_lidar * p(i).template cast<double>());
  }
}

}  // namespace

void DeskewToScanEnd(const std::vector<ImuPoseSample>& samples, const Pose3& T_imu_lidar,
                     const std::vector<LidarPoint>& points, TimeNs t_end_ns,
                     std::vector<Eigen::Vector3d>* p_lidar_end) {
  DeskewPoints(
      samples, T_imu_lidar, points.size(), [&](size_t i) { return points[i].t_ns; },
      [&](size_t i) -> const Eigen::Vector3f& { return points[i].p_lidar; }, t_end_ns, p_lidar_end);
}

void DeskewToScanEnd(const std::vector<ImuPoseSample>& samples, const Pose3& T_imu_lidar,
                     const std::vector<Eigen::Vector3f>& p_lidar, const std::vector<TimeNs>& t_ns,
                     TimeNs t_end_ns, std::vector<Eigen::Vector3d>* p_lidar_end) {
  RVLIO_CHECK(p_lidar.size() == t_ns.size());
  DeskewPoints(
      samples, T_imu_lidar, p_lidar.size(), [&](size_t i) { return t_ns[i]; },
      [&](size_t i) -> const Eigen::Vector3f& { return p_lidar[i]; }, t_end_ns, p_lidar_end);
}

}  // namespace rvlio

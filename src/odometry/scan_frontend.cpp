#include "rvlio/odometry/scan_frontend.h"

#include <utility>

namespace rvlio {
namespace {

constexpr int kRemoveFarEveryScans = 10;  // working-map trimming period

}  // namespace

std::optional<StaticAlignment> StaticInitializer::Add(const ImuSample& imu) {
  samples_.push_back(imu);
  if (imu.t_ns - samples_.front().t_ns < duration_ns_) return std::nullopt;
  const StaticAlignment a = AlignStatic(samples_);
  samples_.clear();
  return a;
}

std::string MovingStartWarning(const StaticAlignment& a) {
  if (!a.moving) return "";
  return "the sequence starts moving (acc std " + std::to_string(a.acc_std) + " m/s^2, gyro std " +
         std::to_string(a.gyro_std) + " rad/s); initialized from the mean IMU values";
}

void TransformPoints(const Pose3& T_world_lidar, const std::vector<Eigen::Vector3d>& p_lidar,
                     std::vector<Eigen::Vector3d>* p_world) {
  p_world->resize(p_lidar.size());
  for (size_t i = 0; i < p_lidar.size(); ++i) (*p_world)[i] = T_world_lidar * p_lidar[i];
}

void WorkingMap::Insert(const std::vector<Eigen::Vector3d>& p_world,
                        const Eigen::Vector3d& sensor_world) {
  map_.Insert(p_world);
  if (++scans_since_trim_ >= kRemoveFarEveryScans) {
    map_.RemoveFar(sensor_world, map_.options().working_radius);
    scans_since_trim_ = 0;
  }
}

bool AcceptImu(const ImuSample& imu, const std::deque<ImuSample>& buffer, OdometryStats* stats) {
  if (!imu.acc_imu.allFinite() || !imu.gyro_imu.allFinite()) {
    ++stats->imu_non_finite;
    return false;
  }
  if (!buffer.empty() && imu.t_ns - buffer.back().t_ns > kNominalScanPeriodNs)
    ++stats->imu_gaps_over_scan;
  return true;
}

void ScanQueue::Add(Scan scan, bool initialized, TimeNs state_time_ns, OdometryStats* stats) {
  ++stats->scans_received;
  if (!initialized || scan.t_start_ns < state_time_ns) {
    ++stats->scans_before_imu;  // no IMU state covers this scan
    return;
  }
  scans_.push_back(std::move(scan));
}

Scan ScanQueue::PopFront() {
  Scan scan = std::move(scans_.front());
  scans_.pop_front();
  return scan;
}

}  // namespace rvlio

#pragma once
// Private (src/live): what `rvlio live` publishes, from two threads
// (docs/live.md "Threads and queues"):
//   - OnImu, on the transport's IMU thread, for every accepted IMU sample:
//     the pose propagated from the latest estimate (ImuPropagator) as the
//     IMU-rate odometry, so it keeps the IMU's rate while the estimator works;
//   - OnResult, on the estimator's thread, for every scan result: the
//     scan-rate odometry and TF first (the latency is measured there), then
//     the registered scan, the status, the path (at most once a second) and,
//     every live.map_period, the map. The propagator restarts from the new
//     estimate before the odometry is published.
#include <chrono>
#include <mutex>
#include <vector>

#include "rvlio/formats/live_source.h"
#include "rvlio/imu/propagator.h"
#include "rvlio/live/live.h"
#include "rvlio/config/configuration.h"
#include "transport.h"

namespace rvlio::live_detail {

class LivePublisher {
 public:
  LivePublisher(Transport* transport, LiveSensorSource* source, const Configuration& options);

  void OnImu(const ImuSample& sample);
  // `result` in the user's frame; the odometry's map is `origin` away from it.
  void OnResult(const ScanResult& result, const Odometry& odometry, const LocalOrigin& origin);
  // The figures of the publications (latency, IMU-rate output).
  void Fill(LiveFigures* figures) const;
  // The stamp of the newest result (-1 before any).
  TimeNs last_result_ns() const { return path_.poses.empty() ? -1 : path_.poses.back().first; }

 private:
  using Clock = std::chrono::steady_clock;
  OdometryMessage Odometry(TimeNs t_ns, const ImuKinematics& state, const Eigen::Vector3d& gyro_imu) const;
  void PublishRegisteredScan(const ScanResult& result, const Scan& scan,
                             const std::vector<ImuSample>& imu);
  void PublishMap(TimeNs t_ns, const rvlio::Odometry& odometry, const LocalOrigin& origin);
  void PublishStatus(const ScanResult& result);

  Transport* transport_;
  LiveSensorSource* source_;
  Configuration options_;
  Pose3 T_imu_lidar_config_;

  mutable std::mutex mutex_;  // guards the propagator and what the IMU thread reads
  ImuPropagator propagator_;
  Eigen::Vector3d bg_imu_ = Eigen::Vector3d::Zero();
  std::array<double, 36> pose_covariance_{};
  int64_t imu_odometry_ = 0, imu_samples_ = 0;
  TimeNs first_imu_ns_ = -1, last_imu_ns_ = -1;
  Clock::time_point first_output_, last_output_;

  // Estimator thread only.
  PathMessage path_;
  std::vector<double> latency_ms_, imu_wait_ms_, after_imu_ms_;
  TimeNs last_map_ns_ = -1;
};

}  // namespace rvlio::live_detail

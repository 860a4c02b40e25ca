#include "publisher.h"

#include <cstring>

#include "rvlio/degeneracy/degeneracy.h"
#include "rvlio/eval/stats.h"
#include "rvlio/imu/pose_history.h"
#include "rvlio/lidar/deskew.h"
#include "rvlio/lidar/extrinsics.h"

namespace rvlio::live_detail {
namespace {

constexpr TimeNs kImuKeepNs = 2000000000;  // IMU samples kept for propagation and deskew (2 s)
constexpr size_t kMaxPathPoses = 10000;    // the published path keeps its newest poses
constexpr TimeNs kPathPeriodNs = 1000000000;  // and is published at most once a second

PoseMessage ToPose(const Eigen::Matrix3d& R, const Eigen::Vector3d& p) {
  PoseMessage m;
  const Eigen::Quaterniond q = Eigen::Quaterniond(R).normalized();
  m.position = {p.x(), p.y(), p.z()};
  m.orientation_xyzw = {q.x(), q.y(), q.z(), q.w()};
  return m;
}

// x y z intensity float32, 16 bytes a point.
struct XyziCloud {
  std::vector<uint8_t> bytes;
  PointCloud2View view;

  XyziCloud(TimeNs t_ns, size_t n) : bytes(n * 16) {
    view.header_stamp_ns = t_ns;
    view.height = 1;
    view.width = static_cast<uint32_t>(n);
    view.point_step = 16;
    view.row_step = static_cast<uint32_t>(n * 16);
    const char* names[] = {"x", "y", "z", "intensity"};
    for (uint32_t i = 0; i < 4; ++i) view.fields.push_back(PointField{names[i], 4 * i, 7, 1});
    view.data = bytes.data();
    view.data_size = bytes.size();
  }
  void Set(size_t i, const Eigen::Vector3d& p, float intensity) {
    const float v[4] = {static_cast<float>(p.x()), static_cast<float>(p.y()),
                        static_cast<float>(p.z()), intensity};
    std::memcpy(bytes.data() + 16 * i, v, sizeof(v));
  }
};

}  // namespace

LivePublisher::LivePublisher(Transport* transport, LiveSensorSource* source,
                             const Configuration& options)
    : transport_(transport),
      source_(source),
      options_(options),
      T_imu_lidar_config_(ImuTLidar(options.extrinsics)),
      propagator_(kImuKeepNs) {
  path_.frame_id = options.live.odom_frame;
}

OdometryMessage LivePublisher::Odometry(TimeNs t_ns, const ImuKinematics& state,
                                        const Eigen::Vector3d& gyro_imu) const {
  OdometryMessage m;
  m.stamp_ns = t_ns;
  m.frame_id = options_.live.odom_frame;
  m.child_frame_id = options_.live.base_frame;
  m.pose = ToPose(state.R_world_imu, state.p_world_imu);
  m.pose_covariance = pose_covariance_;
  const Eigen::Vector3d v_imu = state.R_world_imu.transpose() * state.v_world_imu;
  m.linear_velocity = {v_imu.x(), v_imu.y(), v_imu.z()};
  m.angular_velocity = {gyro_imu.x(), gyro_imu.y(), gyro_imu.z()};
  return m;
}

void LivePublisher::OnImu(const ImuSample& sample) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (first_imu_ns_ < 0) first_imu_ns_ = sample.t_ns;
  last_imu_ns_ = sample.t_ns;
  ++imu_samples_;
  const std::optional<ImuKinematics> state = propagator_.Add(sample);
  if (!state) return;
  transport_->Publish(OdometryTopic::kImuRate,
                      Odometry(sample.t_ns, *state, sample.gyro_imu - bg_imu_));
  const Clock::time_point now = Clock::now();
  if (imu_odometry_++ == 0) first_output_ = now;
  last_output_ = now;
}

void LivePublisher::OnResult(const ScanResult& r, const rvlio::Odometry& odometry,
                             const LocalOrigin& origin) {
  const ImuEstimate estimate = ImuEstimateOf(r);
  std::optional<LiveScanArrival> arrival = source_->TakeArrival(r.t_ns);
  std::vector<ImuSample> imu;
  Eigen::Vector3d gyro_imu = Eigen::Vector3d::Zero();
  OdometryMessage message;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    propagator_.SetEstimate(estimate);
    bg_imu_ = r.bg_imu;
    pose_covariance_.fill(0.0);
    if (r.pose_covariance_world)
      Eigen::Map<Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(pose_covariance_.data()) =
          *r.pose_covariance_world;
    if (arrival) imu = propagator_.Covering(arrival->scan.t_start_ns, r.t_ns);
    if (!imu.empty()) gyro_imu = InterpolateImu(imu, r.t_ns).gyro_imu - r.bg_imu;
    message = Odometry(r.t_ns, estimate.state, gyro_imu);
  }
  transport_->Publish(OdometryTopic::kScanRate, message);
  if (options_.live.publish_tf) {
    TransformMessage tf;
    tf.stamp_ns = r.t_ns;
    tf.frame_id = options_.live.odom_frame;
    tf.child_frame_id = options_.live.base_frame;
    tf.translation = message.pose.position;
    tf.rotation_xyzw = message.pose.orientation_xyzw;
    transport_->PublishTf(tf);
  }
  if (arrival) {
    const auto ms = [](Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); };
    const Clock::time_point now = Clock::now();
    latency_ms_.push_back(ms(now - arrival->arrival));
    imu_wait_ms_.push_back(ms(arrival->covered - arrival->arrival));
    after_imu_ms_.push_back(ms(now - arrival->covered));
  }
  if (arrival && imu.size() >= 2) PublishRegisteredScan(r, arrival->scan, imu);
  if (path_.poses.size() >= kMaxPathPoses) path_.poses.erase(path_.poses.begin());
  path_.poses.emplace_back(r.t_ns, message.pose);
  if (path_.stamp_ns == 0 || r.t_ns - path_.stamp_ns >= kPathPeriodNs) {
    path_.stamp_ns = r.t_ns;
    transport_->Publish(path_);
  }
  PublishStatus(r);
  PublishMap(r.t_ns, odometry, origin);
}

// The scan deskewed to its end by the IMU motion around the estimate (the
// estimator's own deskew: the state at the scan end integrated back over
// the IMU samples), in the world frame at the estimated pose.
void LivePublisher::PublishRegisteredScan(const ScanResult& r, const Scan& scan,
                                          const std::vector<ImuSample>& imu) {
  const ImuPoseHistory history = ImuPoseHistory::Integrate(ImuEstimateOf(r).state, imu,
                                                           scan.t_start_ns, r.bg_imu, r.ba_imu,
                                                           r.g_world);
  const Pose3 T_imu_lidar = r.T_imu_lidar.value_or(T_imu_lidar_config_);
  std::vector<Eigen::Vector3d> p_lidar_end;
  DeskewToScanEnd(history.samples(), T_imu_lidar, scan.points, r.t_ns, &p_lidar_end);
  const Pose3 T_world_lidar = r.T_world_imu * T_imu_lidar;
  XyziCloud cloud(r.t_ns, p_lidar_end.size());
  for (size_t i = 0; i < p_lidar_end.size(); ++i)
    cloud.Set(i, T_world_lidar * p_lidar_end[i], scan.points[i].intensity);
  transport_->Publish(CloudTopic::kRegisteredScan, cloud.view, options_.live.odom_frame);
}

void LivePublisher::PublishMap(TimeNs t_ns, const rvlio::Odometry& odometry,
                               const LocalOrigin& origin) {
  const double period_s = options_.live.map_period;
  if (period_s <= 0.0 || (last_map_ns_ >= 0 && t_ns - last_map_ns_ < SecondsToNs(period_s))) return;
  last_map_ns_ = t_ns;
  MapCloud map = odometry.MapWithAttributes();  // intensity 0 where the recording has none
  origin.ToUser(&map.p);
  XyziCloud cloud(t_ns, map.size());
  for (size_t i = 0; i < map.size(); ++i)
    cloud.Set(i, map.p[i], map.has_intensity ? map.intensity[i] : 0.0f);
  transport_->Publish(CloudTopic::kMap, cloud.view, options_.live.odom_frame);
}

// OK, WARN (degenerate, prediction only) or ERROR (the divergence monitor
// tripped on this scan, or the update diverged).
void LivePublisher::PublishStatus(const ScanResult& r) {
  DiagnosticMessage d;
  d.stamp_ns = r.t_ns;
  d.name = "rvlio: odometry";
  d.hardware_id = options_.live.base_frame;
  const bool diverged = r.status == ScanStatus::kDiverged || r.health.divergence_mask != 0;
  const bool weak = r.degeneracy.degenerate || r.status == ScanStatus::kPredictOnly;
  d.level = diverged ? 2 : weak ? 1 : 0;
  d.message = diverged ? "diverging" : r.degeneracy.degenerate ? "degenerate" : ScanStatusName(r.status);
  const LiveSourceStats s = source_->live_stats();
  d.values = {{"status", ScanStatusName(r.status)},
              {"constraints", std::to_string(r.constraints)},
              {"degenerate", r.degeneracy.degenerate ? "true" : "false"},
              {"weak_directions", std::to_string(r.degeneracy.num_weak)},
              {"divergence_mask", std::to_string(r.health.divergence_mask)},
              {"scans_dropped", std::to_string(s.scans_dropped)},
              {"scan_ms", std::to_string(r.ms)}};
  transport_->Publish(d);
}

void LivePublisher::Fill(LiveFigures* f) const {
  std::lock_guard<std::mutex> lock(mutex_);
  f->imu_odometry = imu_odometry_;
  if (imu_samples_ > 1 && last_imu_ns_ > first_imu_ns_)
    f->imu_input_hz = static_cast<double>(imu_samples_ - 1) / NsToSeconds(last_imu_ns_ - first_imu_ns_);
  const double output_s = std::chrono::duration<double>(last_output_ - first_output_).count();
  if (imu_odometry_ > 1 && output_s > 0.0)
    f->imu_odometry_hz = static_cast<double>(imu_odometry_ - 1) / output_s;
  const ErrorStats latency = ComputeStats(latency_ms_);
  f->latency_samples = static_cast<int64_t>(latency.count);
  f->latency_median_ms = latency.median;
  f->latency_p95_ms = latency.p95;
  f->latency_max_ms = latency.max;
  f->imu_wait_median_ms = ComputeStats(imu_wait_ms_).median;
  const ErrorStats after_imu = ComputeStats(after_imu_ms_);
  f->after_imu_median_ms = after_imu.median;
  f->after_imu_p95_ms = after_imu.p95;
}

}  // namespace rvlio::live_detail

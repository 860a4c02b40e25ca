#include "rvlio/sim/simulator.h"

#include <cmath>

#include "rvlio/sim/imu_sim.h"
#include "rvlio/sim/random.h"

namespace rvlio::sim {

namespace {
constexpr uint64_t kScanStreamBase = 1000;  // scan k draws noise from stream kScanStreamBase + k

Pose3 ExtrinsicPose(const ExtrinsicsOptions& e) {
  const auto& q = e.rotation_xyzw;
  return Pose3(Eigen::Quaterniond(q[3], q[0], q[1], q[2]),
               Eigen::Vector3d(e.translation[0], e.translation[1], e.translation[2]));
}
}  // namespace

StatusOr<std::unique_ptr<Simulator>> Simulator::Create(const SimOptions& options) {
  SimOptions copy = options;
  Status s = copy.Validate();
  if (!s.ok()) return s;
  return std::unique_ptr<Simulator>(new Simulator(copy));
}

Simulator::Simulator(const SimOptions& options) : options_(options), lidar_(options.lidar) {
  const uint64_t seed = static_cast<uint64_t>(options.seed);
  t0_ns_ = SecondsToNs(options.start_time);
  t_end_ns_ = t0_ns_ + SecondsToNs(options.duration);
  T_imu_lidar_ = ExtrinsicPose(options.extrinsics.imu_T_lidar);
  trajectory_ =
      std::make_unique<FlightTrajectory>(*ParseWaypoints(options.trajectory.waypoints),
                                         options.trajectory, options.imu.gravity, t0_ns_, seed);
  layout_ = MakeLayout(options.world);
  world_ = BuildWorld(options.world, trajectory_->SamplePath(0.1), seed);
  scan_count_ = (t_end_ns_ - t0_ns_) / lidar_.period_ns();
  ImuSimulator imu(*trajectory_, options.imu, seed);
  while (imu.SampleTime(imu_count_) <= t_end_ns_) ++imu_count_;
}

Scan Simulator::SimulateScan(int64_t k) const {
  Rng rng =
      Rng::Stream(static_cast<uint64_t>(options_.seed), kScanStreamBase + static_cast<uint64_t>(k));
  return CastScan(world_, *trajectory_, lidar_, options_.lidar, T_imu_lidar_, ScanStartTime(k),
                  rng);
}

bool Simulator::Run(const ImuCallback& on_imu, const ScanCallback& on_scan) const {
  ImuSimulator imu(*trajectory_, options_.imu, static_cast<uint64_t>(options_.seed));
  int64_t imu_done = 0;
  auto emit_imu_until = [&](TimeNs t_ns) {
    for (; imu_done < imu_count_ && imu.NextTime() <= t_ns; ++imu_done)
      if (!on_imu(imu.Next())) return false;
    return true;
  };
  for (int64_t k = 0; k < scan_count_; ++k) {
    if (!emit_imu_until(ScanStartTime(k) + lidar_.period_ns())) return false;
    Scan scan = SimulateScan(k);
    ShiftScanTime(-LidarClockOffsetNs(scan.t_start_ns), &scan);
    if (!on_scan(scan, lidar_.rows(), lidar_.cols())) return false;
  }
  return emit_imu_until(t_end_ns_);
}

// The LiDAR clock's offset at true time t_ns: constant plus a linear drift
// (one value per scan: the drift over a sweep is far below a nanosecond's
// worth of motion for any realistic rate).
TimeNs Simulator::LidarClockOffsetNs(TimeNs t_ns) const {
  const double drift_s = options_.lidar.time_offset_drift * NsToSeconds(t_ns - t0_ns_);
  return SecondsToNs(options_.lidar.time_offset + drift_s);
}

Trajectory Simulator::GroundTruth(double rate_hz) const {
  Trajectory out;
  const double step_ns = 1e9 / rate_hz;
  for (int64_t i = 0;; ++i) {
    const TimeNs t = t0_ns_ + static_cast<TimeNs>(std::llround(i * step_ns));
    if (t > t_end_ns_) break;
    const TruthState s = trajectory_->At(t);
    out.push_back({t, s.T_world_imu.t, s.T_world_imu.quaternion()});
  }
  return out;
}

}  // namespace rvlio::sim

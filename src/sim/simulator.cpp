#include "rvlio/sim/simulator.h"

#include <cmath>

#include "rvlio/lidar/extrinsics.h"
#include "rvlio/sim/imu_sim.h"
#include "rvlio/sim/random.h"

namespace rvlio::sim {

namespace {
constexpr uint64_t kScanStreamBase = 1000;  // scan k draws noise from stream kScanStreamBase + k
constexpr double kPathStep = 0.1;           // m between flight path samples for the world builder

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
  const uint64_t flight_seed = options.FlightSeed();
  t0_ns_ = SecondsToNs(options.start_time);
  t_end_ns_ = t0_ns_ + SecondsToNs(options.duration);
  T_imu_lidar_ = ExtrinsicPose(options.extrinsics.imu_T_lidar);
  trajectory_ = std::make_unique<FlightTrajectory>(*ParseWaypoints(options.trajectory.waypoints),
                                                   options.trajectory, options.imu.gravity, t0_ns_,
                                                   flight_seed);
  layout_ = MakeLayout(options.world);
  // The world depends on the world seed and the flight path (features keep
  // clear of it), which the flight seed does not change.
  world_ = BuildWorld(options.world, trajectory_->SamplePath(kPathStep),
                      static_cast<uint64_t>(options.seed));
  scan_count_ = (t_end_ns_ - t0_ns_) / lidar_.period_ns();
  ImuSimulator imu(*trajectory_, options.imu, flight_seed);
  while (imu.SampleTime(imu_count_) <= t_end_ns_) ++imu_count_;
}

StatusOr<SurveyResult> Simulator::Survey() const {
  const uint64_t seed = static_cast<uint64_t>(options_.seed);
  if (options_.survey.deformed || options_.world.deformation.amplitude == 0.0)
    return SurveyWorld(world_, layout_, options_.survey, seed);
  SimWorldOptions undeformed = options_.world;
  undeformed.deformation.amplitude = 0.0;
  const World world = BuildWorld(undeformed, trajectory_->SamplePath(kPathStep), seed);
  return SurveyWorld(world, layout_, options_.survey, seed);
}

Scan Simulator::SimulateScan(int64_t k, std::vector<SurfaceHit>* truth) const {
  Rng rng = Rng::Stream(options_.FlightSeed(), kScanStreamBase + static_cast<uint64_t>(k));
  return CastScan(world_, *trajectory_, lidar_, options_.lidar, T_imu_lidar_, ScanStartTime(k),
                  rng, truth);
}

bool Simulator::Run(const ImuCallback& on_imu, const ScanCallback& on_scan,
                    const TruthCallback& on_truth) const {
  std::vector<SurfaceHit> truth;
  ImuSimulator imu(*trajectory_, options_.imu, options_.FlightSeed());
  int64_t imu_done = 0;
  auto emit_imu_until = [&](TimeNs t_ns) {
    for (; imu_done < imu_count_ && imu.NextTime() <= t_ns; ++imu_done)
      if (!on_imu(imu.Next())) return false;
    return true;
  };
  for (int64_t k = 0; k < scan_count_; ++k) {
    if (!emit_imu_until(ScanStartTime(k) + lidar_.period_ns())) return false;
    Scan scan = SimulateScan(k, on_truth ? &truth : nullptr);
    if (on_truth) on_truth(scan, &truth);
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

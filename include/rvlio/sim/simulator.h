#pragma once
// The deterministic simulator: world + flight + LiDAR + IMU. Data
// is generated in time order through callbacks (a 60 s OS1-32 sequence does
// not fit in memory as a whole). Same options and seed -> identical output.
//
// Timing: the first IMU sample and the first scan start at t0 =
// options.start_time; IMU samples every 1/imu.rate; scans start on the fixed
// grid t0 + k / lidar.rate and are emitted after every IMU sample up to their
// end (start + period). Only whole scans within [t0, t0 + duration] are made.
//
// Seeds: the world (shell relief, features) comes from options.seed; the
// flight (yaw and sway phases, IMU noise, LiDAR noise) from
// options.FlightSeed(), which is the world seed unless flight_seed is set.
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/math/pose.h"
#include "rvlio/sim/lidar_sim.h"
#include "rvlio/sim/options.h"
#include "rvlio/sim/survey.h"
#include "rvlio/sim/trajectory.h"
#include "rvlio/sim/world.h"
#include "rvlio/sim/world_builder.h"

namespace rvlio::sim {

class Simulator {
 public:
  // Callbacks return false to stop the run early.
  using ImuCallback = std::function<bool(const ImuSample&)>;
  using ScanCallback = std::function<bool(const Scan&, int rows, int cols)>;
  // The true hits of a scan (lidar_sim.h), with the scan in true time (before
  // the LiDAR clock offset is applied), just before on_scan gets it.
  using TruthCallback = std::function<void(const Scan&, std::vector<SurfaceHit>*)>;

  // Validates the options (InvalidInput naming the key) and builds the world.
  static StatusOr<std::unique_ptr<Simulator>> Create(const SimOptions& options);

  // Emits every IMU sample and scan in time order. True if it ran to the end.
  // With on_truth, every scan's true hits go there first.
  bool Run(const ImuCallback& on_imu, const ScanCallback& on_scan,
           const TruthCallback& on_truth = nullptr) const;
  // Scan k alone (the same as the k-th scan of Run; noise from its own stream);
  // with `truth`, its true hits too.
  Scan SimulateScan(int64_t k, std::vector<SurfaceHit>* truth = nullptr) const;
  // The reference map (options().survey): a static survey of the world,
  // undeformed unless survey.deformed. Depends on the world seed only, not on
  // the flight seed. InvalidInput when the crop leaves nothing to survey.
  StatusOr<SurveyResult> Survey() const;

  TruthState TruthAt(TimeNs t_ns) const { return trajectory_->At(t_ns); }
  // T_world_imu from t0 to t0 + duration every 1/rate_hz s.
  Trajectory GroundTruth(double rate_hz) const;

  const SimOptions& options() const { return options_; }
  const World& world() const { return world_; }
  const WorldLayout& layout() const { return layout_; }
  const FlightTrajectory& trajectory() const { return *trajectory_; }
  const LidarModel& lidar() const { return lidar_; }
  const Pose3& T_imu_lidar() const { return T_imu_lidar_; }
  TimeNs start_time_ns() const { return t0_ns_; }
  TimeNs end_time_ns() const { return t_end_ns_; }
  TimeNs ScanStartTime(int64_t k) const { return t0_ns_ + k * lidar_.period_ns(); }
  int64_t scan_count() const { return scan_count_; }
  int64_t imu_count() const { return imu_count_; }
  // The LiDAR clock's offset at true time t_ns (lidar.time_offset plus
  // lidar.time_offset_drift since the first sample): Run() writes a scan's
  // stamps as true time minus this value at the scan start.
  TimeNs LidarClockOffsetNs(TimeNs t_ns) const;

 private:
  explicit Simulator(const SimOptions& options);

  SimOptions options_;
  TimeNs t0_ns_ = 0, t_end_ns_ = 0;
  Pose3 T_imu_lidar_;
  std::unique_ptr<FlightTrajectory> trajectory_;
  WorldLayout layout_;
  World world_;
  LidarModel lidar_;
  int64_t scan_count_ = 0, imu_count_ = 0;
};

}  // namespace rvlio::sim

// Runs the IESKF on a simulated tunnel through rvlio::Odometry and prints
// the ATE against the simulator's ground truth. Needs only rvlio::core.
//   ieskf_tunnel [duration_s]   (default 8 s of the "tunnel" preset)
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "rvlio/eval/evaluate.h"
#include "rvlio/odometry/odometry.h"
#include "rvlio/sim/presets.h"
#include "rvlio/sim/simulator.h"
#include "rvlio/version.h"

namespace {

// The estimator's sensor settings as simulated (what `rvlio simulate` writes
// to NAME.yaml): extrinsics, IMU noise, gravity and LiDAR ranges.
rvlio::OdometryOptions SensorOptions(const rvlio::SimOptions& sim) {
  rvlio::OdometryOptions o;  // backend "ieskf", the paper's defaults
  o.extrinsics = sim.extrinsics;
  o.imu.gyro_noise_density = std::max(sim.imu.gyro_noise_density, 1e-9);
  o.imu.accel_noise_density = std::max(sim.imu.accel_noise_density, 1e-9);
  o.imu.gyro_bias_random_walk = std::max(sim.imu.gyro_bias_random_walk, 1e-9);
  o.imu.accel_bias_random_walk = std::max(sim.imu.accel_bias_random_walk, 1e-9);
  o.imu.gravity = sim.imu.gravity;
  o.lidar.min_range = sim.lidar.min_range;
  o.lidar.max_range = sim.lidar.max_range;
  return o;
}

int Fail(const rvlio::Status& s) {
  std::fprintf(stderr, "ieskf_tunnel: error: %s\n", s.message().c_str());
  return s.code() == rvlio::StatusCode::kInternal ? 1 : 2;  // bad input or I/O: 2
}

}  // namespace

int main(int argc, char** argv) {
  std::printf("rvlio %s (headers %s)\n", rvlio::LibraryVersion(), RVLIO_VERSION);
  rvlio::StatusOr<rvlio::SimOptions> sim = rvlio::sim::PresetOptions("tunnel");
  if (!sim.ok()) return Fail(sim.status());
  sim->duration = argc > 1 ? std::atof(argv[1]) : 8.0;
  sim->lidar.columns = 512;  // a lighter scan for a quick example
  auto simulator = rvlio::sim::Simulator::Create(*sim);
  if (!simulator.ok()) return Fail(simulator.status());
  auto odometry = rvlio::Odometry::Create(SensorOptions(*sim));
  if (!odometry.ok()) return Fail(odometry.status());

  // The simulator emits IMU samples and scans in time order, as a driver would.
  rvlio::Odometry& odo = **odometry;
  std::vector<rvlio::ScanResult> results;
  (*simulator)->Run(
      [&](const rvlio::ImuSample& imu) {
        odo.AddImu(imu);
        odo.Poll(&results);
        return true;
      },
      [&](const rvlio::Scan& scan, int /*rows*/, int /*cols*/) {
        odo.AddScan(scan);
        odo.Poll(&results);
        return true;
      });
  odo.Finish(&results);

  rvlio::Trajectory estimate;
  for (const rvlio::ScanResult& r : results)
    estimate.push_back({r.t_ns, r.T_world_imu.t, r.T_world_imu.quaternion()});
  rvlio::EvalOptions eval;  // SE(3) alignment, as evo_ape --align
  auto ate = rvlio::Evaluate((*simulator)->GroundTruth(100.0), estimate, eval);
  if (!ate.ok()) return Fail(ate.status());
  int rv_active = 0;
  for (const rvlio::ScanResult& r : results) rv_active += r.rv.active ? 1 : 0;
  std::printf("ieskf_tunnel: %zu scans (%d RV-active), %.1f s: ATE rmse %.4f m, max %.4f m, "
              "end-point error %.4f m\n",
              results.size(), rv_active, sim->duration, ate->ape_m.rmse, ate->ape_m.max,
              ate->end_point_error_m);
  return results.empty() ? 1 : 0;
}

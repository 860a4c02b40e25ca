#include "rvlio/refine/divergence.h"

#include <cmath>
#include <cstddef>

namespace rvlio {

DivergenceReport CheckRefineResult(const RefineResult& result, const DivergenceOptions& options,
                                   double lidar_noise_m, double gravity_mps2) {
  DivergenceMonitor monitor(options, lidar_noise_m, gravity_mps2);
  const RefineRound* last = result.rounds.empty() ? nullptr : &result.rounds.back();
  for (size_t i = 0; i < result.trajectory.size(); ++i) {
    HealthSample s;
    s.t_ns = result.trajectory[i].t_ns;
    s.p_world_imu = result.trajectory[i].p_world_imu;
    if (i < result.v_world_imu.size()) s.v_world_imu = result.v_world_imu[i];
    if (last != nullptr && last->points > 0) {
      constexpr int kPerMillion = 1000000;  // the round's ratio in parts per million
      s.associated = true;
      s.points = kPerMillion;
      s.constraints = static_cast<int>(std::lround(
          kPerMillion * static_cast<double>(last->constraints) / static_cast<double>(last->points)));
    }
    monitor.Check(s);
  }
  return monitor.report();
}

}  // namespace rvlio

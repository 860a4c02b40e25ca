// Simulator throughput: one OS1-32 scan (32 x 1024 rays) at representative
// places of the tunnel preset (entrance clutter, sparse part) and of the hall,
// and IMU samples. `rvlio simulate` prints the end-to-end figure.
#include <benchmark/benchmark.h>

#include "rvlio/sim/imu_sim.h"
#include "rvlio/sim/presets.h"
#include "rvlio/sim/simulator.h"

namespace {

using rvlio::sim::Simulator;

std::unique_ptr<Simulator> Make(const char* preset) {
  return std::move(Simulator::Create(*rvlio::sim::PresetOptions(preset))).value();
}

void BM_TunnelScan(benchmark::State& state) {
  static const std::unique_ptr<Simulator> sim = Make("tunnel");
  const int64_t k = state.range(0);
  for (auto _ : state) benchmark::DoNotOptimize(sim->SimulateScan(k));
  state.SetItemsProcessed(state.iterations() * 32 * 1024);
}
// Scan index = 10 x seconds: at rest in the entrance (0), mid-flight in the
// sparse part (300), at the far waypoint (500).
BENCHMARK(BM_TunnelScan)->Arg(0)->Arg(300)->Arg(500)->Unit(benchmark::kMillisecond);

void BM_HallScan(benchmark::State& state) {
  static const std::unique_ptr<Simulator> sim = Make("hall");
  for (auto _ : state) benchmark::DoNotOptimize(sim->SimulateScan(state.range(0)));
  state.SetItemsProcessed(state.iterations() * 32 * 1024);
}
BENCHMARK(BM_HallScan)->Arg(100)->Arg(400)->Unit(benchmark::kMillisecond);

void BM_ImuSample(benchmark::State& state) {
  static const std::unique_ptr<Simulator> sim = Make("tunnel");
  rvlio::sim::ImuSimulator imu(sim->trajectory(), sim->options().imu, 1);
  for (auto _ : state) benchmark::DoNotOptimize(imu.Next());
}
BENCHMARK(BM_ImuSample);

}  // namespace

BENCHMARK_MAIN();

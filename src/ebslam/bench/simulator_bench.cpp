// Event simulator throughput on the floor-robot scenario (thesis 6.5.3): simulated seconds per
// wall-clock second on one core, for a procedural lines-and-circles ceiling and a straight-and-
// turning robot path at pioneer-like speed (0.3 m/s, 0.5 rad/s).

#include <cmath>

#include <benchmark/benchmark.h>

#include "ebslam/simulation/simulator.h"
#include "ebslam/simulation/simulator_scenes.h"

namespace {

ebslam::Trajectory robotPath(double duration_s) {
  ebslam::Trajectory path;
  const int steps = static_cast<int>(duration_s * 100.0);
  for (int i = 0; i <= steps; ++i) {
    const double t = 0.01 * i;
    path.push_back(ebslam::se2ToFloorPose(t, 0.3 * t, 0.4 * std::sin(0.5 * t), 0.5 * t));
  }
  return path;
}

// Argument 0: supersampling factor.
void BM_SimulateFloorRobot(benchmark::State& state) {
  const double duration_s = 2.0;
  ebslam::SimulatorConfig config;
  config.supersampling = static_cast<int>(state.range(0));
  const ebslam::Trajectory path = robotPath(duration_s);
  const ebslam::Scene scene =
      ebslam::makeCeilingScene(ebslam::makeLinesAndCirclesTexture(),
                               ebslam::visibleCeilingRegion(path, config.camera), 0.01);
  const ebslam::EventSimulator simulator(config);
  std::size_t events = 0;
  std::size_t steps = 0;
  for (auto _ : state) {
    std::size_t count = 0;
    const ebslam::SimulationResult result =
        simulator.simulate(scene, path, 0.0, duration_s,
                           [&count](const ebslam::EventVector& batch) { count += batch.size(); });
    events += count;
    steps += result.render_steps;
    benchmark::DoNotOptimize(count);
  }
  const double iterations = static_cast<double>(state.iterations());
  state.counters["realtime_factor"] =
      benchmark::Counter(duration_s * iterations, benchmark::Counter::kIsRate);
  state.counters["events_per_s"] =
      benchmark::Counter(static_cast<double>(events), benchmark::Counter::kIsRate);
  state.counters["renders_per_s"] =
      benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsRate);
  state.counters["sim_events_per_sim_s"] = static_cast<double>(events) / iterations / duration_s;
}
BENCHMARK(BM_SimulateFloorRobot)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();

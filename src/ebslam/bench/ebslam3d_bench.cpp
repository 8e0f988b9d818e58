// Speed of EB-SLAM-3D (thesis 8.3) on one core in events per second and as a real-time factor
// (event-stream duration / processing time, the thesis' "relative realtime factor" of table
// 8.1), for the default and the fast parameter set, e.g.
//   ebslam_ebslam3d_bench --benchmark_counters_tabular=true
// The stream: synthetic depth events (synthetic_depth_events.h) along a 4 s hand-held-like path
// (0.4 m, turns of 0.35 rad, starting and ending at rest) in a textured room; every iteration runs
// a fresh filter over the whole stream (construction not timed). Counters: events_per_s,
// stream_events_per_s, realtime_factor, thesis_realtime_factor (table 8.1: 1.4-2.5x default,
// 16-27x fast; 2.0 and 20 used here), peak_map_mib.

#include <benchmark/benchmark.h>

#include <cmath>

#include "ebslam/simulation/synthetic_depth_events.h"
#include "ebslam/slam/ebslam3d.h"

namespace {

using namespace ebslam;

struct Scenario {
  Trajectory path;
  PointEventVector events;
  double duration_s = 4.0;
  Scenario() {
    for (int k = 0; k <= 400; ++k) {
      const double t = duration_s * k / 400.0;
      const double u = 0.5 * (1.0 - std::cos(M_PI * t / duration_s));
      StampedPose p;
      p.t_s = t;
      p.position = Eigen::Vector3d(0.4 * u, 0.1 * std::sin(M_PI * u), 0.1 * u);
      p.orientation = Eigen::AngleAxisd(0.35 * u, Eigen::Vector3d::UnitY()) *
                      Eigen::AngleAxisd(0.2 * std::sin(M_PI * u), Eigen::Vector3d::UnitX());
      path.push_back(p);
    }
    const auto scene = makeSyntheticRoom(path);
    events = simulateDepthEvents(scene, SyntheticDepthSensor{}, path, 0.0, duration_s);
  }
  double streamSeconds() const {
    return 1e-6 * static_cast<double>(events.back().t_us - events.front().t_us);
  }
};

const Scenario& scenario() {
  static const Scenario s;
  return s;
}

void run(benchmark::State& state, const Ebslam3dConfig& config, double thesis_rtf) {
  const Scenario& s = scenario();
  std::size_t peak = 0;
  for (auto _ : state) {
    state.PauseTiming();
    EventSlam3d slam(config);
    state.ResumeTiming();
    slam.process(s.events);
    benchmark::DoNotOptimize(slam.estimate());
    state.PauseTiming();
    peak = slam.peakMemoryBytes();
    state.ResumeTiming();
  }
  const double events = static_cast<double>(state.iterations()) * s.events.size();
  state.SetItemsProcessed(static_cast<int64_t>(events));
  state.counters["events_per_s"] = benchmark::Counter(events, benchmark::Counter::kIsRate);
  state.counters["stream_events_per_s"] = static_cast<double>(s.events.size()) / s.streamSeconds();
  // Stream seconds processed per second of CPU time.
  state.counters["realtime_factor"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * s.streamSeconds(), benchmark::Counter::kIsRate);
  state.counters["thesis_realtime_factor"] = thesis_rtf;
  state.counters["peak_map_mib"] = static_cast<double>(peak) / (1024.0 * 1024.0);
}

void BM_Ebslam3dDefault(benchmark::State& state) { run(state, Ebslam3dConfig::defaults(), 2.0); }
BENCHMARK(BM_Ebslam3dDefault)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

void BM_Ebslam3dFast(benchmark::State& state) { run(state, Ebslam3dConfig::fast(), 20.0); }
BENCHMARK(BM_Ebslam3dFast)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

// The thesis' 8.4 set on the same stream, side by side with the presets (table 8.1: 1.4-2.5x).
void BM_Ebslam3dThesis(benchmark::State& state) { run(state, Ebslam3dConfig::thesis(), 2.0); }
BENCHMARK(BM_Ebslam3dThesis)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

// The thesis' sweep of the particle count (fig. 8.12, top), other parameters at the default set.
void BM_Ebslam3dParticles(benchmark::State& state) {
  Ebslam3dConfig c = Ebslam3dConfig::defaults();
  c.num_particles = static_cast<int>(state.range(0));
  run(state, c, 0.0);
}
BENCHMARK(BM_Ebslam3dParticles)
    ->ArgName("N")
    ->Arg(25)
    ->Arg(50)
    ->Arg(200)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime();

}  // namespace
BENCHMARK_MAIN();

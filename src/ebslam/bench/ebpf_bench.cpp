// Speed of EB-PF and EB-SLAM-2D in events per second on one core, next to the thesis' figures
// (table 6.3: EB-PF, 2.53 GHz single core; table 7.1: EB-SLAM-2D), e.g.
//   ebslam_ebpf_bench --benchmark_counters_tabular=true
// The event stream is a synthetic ceiling run (test/synthetic_ceiling.h: lines and circles,
// 0.6 m loop with turning, about 180k events); every iteration processes the whole stream with a
// fresh filter (construction not timed). Counters: events_per_s (items_per_second),
// thesis_events_per_s and speedup = events_per_s / thesis_events_per_s.

#include <benchmark/benchmark.h>

#include <map>
#include <utility>

#include "../test/synthetic_ceiling.h"
#include "ebslam/ebpf.h"
#include "ebslam/ebslam2d.h"

namespace {

using namespace ebslam;

struct Scenario {
  CeilingCamera camera{CameraModel{}, 2.59};
  testing::SyntheticCeiling ceiling = testing::makeSyntheticCeiling(4.0, 0.01, 11);
  EventVector events = testing::generateSyntheticEvents(
      ceiling, camera, [](double t) { return testing::loopPath(t); }, 0.0, 2.0);
  GridMap2f likelihood = makeEdgeLikelihoodMap(ceiling.edges, ceiling.metres_per_pixel,
                                               ceiling.origin_centre_m, 0.5 * camera.wTrig());
};

const Scenario& scenario() {
  static const Scenario s;
  return s;
}

// Table 6.3 (EB-PF) [events/s] by (B, N).
double thesisEbpf(int b, int n) {
  static const std::map<std::pair<int, int>, double> t{{{1, 50}, 34400},  {{1, 100}, 18100},
                                                       {{1, 250}, 7500},  {{3, 50}, 74800},
                                                       {{3, 100}, 40400}, {{3, 250}, 17200}};
  const auto it = t.find({b, n});
  return it == t.end() ? 0.0 : it->second;
}

// Table 7.1 (EB-SLAM-2D) [events/s] by N (batch size not stated in the thesis).
double thesisSlam(int n) {
  static const std::map<int, double> t{{5, 87800}, {10, 80700}, {25, 65600}, {75, 38800}};
  const auto it = t.find(n);
  return it == t.end() ? 0.0 : it->second;
}

void setCounters(benchmark::State& state, double thesis) {
  const double events = static_cast<double>(state.iterations()) * scenario().events.size();
  state.SetItemsProcessed(static_cast<int64_t>(events));
  state.counters["events_per_s"] = benchmark::Counter(events, benchmark::Counter::kIsRate);
  if (thesis > 0.0) {
    state.counters["thesis_events_per_s"] = thesis;
    state.counters["speedup"] = benchmark::Counter(events / thesis, benchmark::Counter::kIsRate);
  }
}

void BM_Ebpf(benchmark::State& state) {
  const Scenario& s = scenario();
  EbpfConfig config;
  config.filter.batch_size = static_cast<int>(state.range(0));
  config.filter.num_particles = static_cast<int>(state.range(1));
  config.filter.g0 = 100.0;
  for (auto _ : state) {
    state.PauseTiming();
    EventParticleFilter filter(config, s.camera, s.likelihood, testing::loopPath(0.0));
    state.ResumeTiming();
    filter.process(s.events);
    benchmark::DoNotOptimize(filter.estimate());
  }
  setCounters(state, thesisEbpf(config.filter.batch_size, config.filter.num_particles));
}
BENCHMARK(BM_Ebpf)
    ->ArgNames({"B", "N"})
    ->ArgsProduct({{1, 3}, {50, 100, 250}})
    ->Unit(benchmark::kMillisecond);

void BM_Ebslam2d(benchmark::State& state) {
  const Scenario& s = scenario();
  Ebslam2dConfig config;
  config.filter.batch_size = static_cast<int>(state.range(0));
  config.filter.num_particles = static_cast<int>(state.range(1));
  config.filter.g0 = 100.0;
  for (auto _ : state) {
    state.PauseTiming();
    EventSlam2d slam(config, s.camera, testing::loopPath(0.0));
    state.ResumeTiming();
    slam.process(s.events);
    benchmark::DoNotOptimize(slam.estimate());
  }
  setCounters(state, thesisSlam(config.filter.num_particles));
}
BENCHMARK(BM_Ebslam2d)
    ->ArgNames({"B", "N"})
    ->ArgsProduct({{1, 3}, {5, 10, 25, 50, 75, 100, 250}})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

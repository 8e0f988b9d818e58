// Speed of EB-PF and EB-SLAM-2D in events per second on one core, next to the thesis' figures
// (table 6.3: EB-PF, 2.53 GHz single core; table 7.1: EB-SLAM-2D), e.g.
//   ebslam_ebpf_bench --benchmark_counters_tabular=true
// The event stream is a synthetic ceiling run (test/synthetic_ceiling.h: lines and circles,
// 0.6 m loop with turning, about 180k events); every iteration processes the whole stream with a
// fresh filter (construction not timed). Counters: events_per_s (items_per_second),
// thesis_events_per_s and speedup = events_per_s / thesis_events_per_s.
// BM_BackgroundActivityFilter: the noise filter (event_denoiser.h) on the same stream with 1 Hz
// of background activity per pixel added, its cost per event beside the filters' own
// (ns_per_event; 1e9 / events_per_s of the others).

#include <benchmark/benchmark.h>

#include <algorithm>
#include <map>
#include <random>
#include <utility>

#include "../test/synthetic_ceiling.h"
#include "ebslam/events/event_denoiser.h"
#include "ebslam/slam/ebpf.h"
#include "ebslam/slam/ebslam2d.h"

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

// The synthetic stream with uniform background activity of `rate_hz` per pixel, merged in time.
EventVector withNoise(const EventVector& signal, double rate_hz, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const double t0 = static_cast<double>(signal.front().t_us);
  const double t1 = static_cast<double>(signal.back().t_us);
  std::exponential_distribution<double> gap(rate_hz * 128 * 128 * 1e-6);  // per us
  std::uniform_int_distribution<int> pixel(0, 127);
  EventVector events = signal;
  for (double t = t0 + gap(rng); t < t1; t += gap(rng)) {
    Event e;
    e.t_us = static_cast<std::int64_t>(t);
    e.x = static_cast<std::uint16_t>(pixel(rng));
    e.y = static_cast<std::uint16_t>(pixel(rng));
    e.polarity = (rng() & 1u) != 0;
    events.push_back(e);
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const Event& a, const Event& b) { return a.t_us < b.t_us; });
  return events;
}

void BM_BackgroundActivityFilter(benchmark::State& state) {
  static const EventVector events = withNoise(scenario().events, 1.0, 5);
  BackgroundActivityFilterConfig config;
  config.refractory_filter = state.range(0) != 0;
  EventVector passed;
  passed.reserve(events.size());
  for (auto _ : state) {
    state.PauseTiming();
    BackgroundActivityFilter filter(config, SensorSize{128, 128});
    passed.clear();
    state.ResumeTiming();
    filter.filter(events, passed);
    benchmark::DoNotOptimize(passed.data());
  }
  const double n = static_cast<double>(state.iterations()) * events.size();
  state.SetItemsProcessed(static_cast<int64_t>(n));
  state.counters["events_per_s"] = benchmark::Counter(n, benchmark::Counter::kIsRate);
  state.counters["ns_per_event"] =
      benchmark::Counter(n * 1e-9, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_BackgroundActivityFilter)->ArgName("refractory")->Arg(0)->Arg(1);

}  // namespace

BENCHMARK_MAIN();

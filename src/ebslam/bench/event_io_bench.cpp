// Event file throughput: events per second written and read, per format, through the page
// cache (files in /dev/shm when it exists, so the figures are the codec's, not the disk's).
//   ebslam_event_io_bench --benchmark_counters_tabular=true

#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include "ebslam/events/event_io.h"

namespace {

constexpr std::size_t kEvents = 1 << 20;

const ebslam::EventVector& benchEvents() {
  static const ebslam::EventVector events = [] {
    std::mt19937 rng(42);
    std::exponential_distribution<double> gap(1.0 / 5.0);  // 200k events/s, eDVS at 4 Mbit/s
    ebslam::EventVector v(kEvents);
    double t = 1.0e6;
    for (auto& e : v) {
      t += gap(rng);
      e.t_us = static_cast<std::int64_t>(t);
      e.x = static_cast<std::uint16_t>(rng() % 128);
      e.y = static_cast<std::uint16_t>(rng() % 128);
      e.polarity = (rng() & 1u) != 0;
    }
    return v;
  }();
  return events;
}

std::string benchPath(ebslam::EventFileFormat format) {
  const std::filesystem::path dir = std::filesystem::is_directory("/dev/shm")
                                        ? "/dev/shm"
                                        : std::filesystem::temp_directory_path();
  return (dir /
          ("ebslam_event_io_bench_" + std::to_string(::getpid()) + "_" + ebslam::toString(format)))
      .string();
}

void BM_Write(benchmark::State& state, ebslam::EventFileFormat format) {
  const auto& events = benchEvents();
  const std::string path = benchPath(format);
  for (auto _ : state) ebslam::writeEventFile(path, events, {128, 128}, format);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * events.size()));
  state.counters["bytes_per_event"] =
      static_cast<double>(std::filesystem::file_size(path)) / static_cast<double>(events.size());
  std::filesystem::remove(path);
}

void BM_Read(benchmark::State& state, ebslam::EventFileFormat format) {
  const auto& events = benchEvents();
  const std::string path = benchPath(format);
  ebslam::writeEventFile(path, events, {128, 128}, format);
  for (auto _ : state) {
    const ebslam::EventReadResult r = ebslam::readEventFile(path, format);
    if (r.events.size() != events.size() || r.error) state.SkipWithError("read mismatch");
    benchmark::DoNotOptimize(r.events.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * events.size()));
  std::filesystem::remove(path);
}

// Streaming in batches of 4096 events (constant memory), as the offline runners do.
void BM_StreamRead(benchmark::State& state, ebslam::EventFileFormat format) {
  const auto& events = benchEvents();
  const std::string path = benchPath(format);
  ebslam::writeEventFile(path, events, {128, 128}, format);
  for (auto _ : state) {
    ebslam::EventFileReader reader(path);
    ebslam::EventVector batch;
    std::size_t total = 0;
    while (reader.next(batch, 4096) > 0) total += batch.size();
    if (total != events.size()) state.SkipWithError("read mismatch");
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * events.size()));
  std::filesystem::remove(path);
}

BENCHMARK_CAPTURE(BM_Write, binary, ebslam::EventFileFormat::kBinary)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Write, text, ebslam::EventFileFormat::kText)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Write, rpg, ebslam::EventFileFormat::kRpgText)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Read, binary, ebslam::EventFileFormat::kBinary)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Read, text, ebslam::EventFileFormat::kText)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Read, rpg, ebslam::EventFileFormat::kRpgText)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_StreamRead, binary, ebslam::EventFileFormat::kBinary)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_StreamRead, text, ebslam::EventFileFormat::kText)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

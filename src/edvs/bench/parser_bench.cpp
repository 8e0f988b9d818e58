// Parser throughput per event format [events/s], fed in reads of 4 KiB as from a serial port.
// 12 Mbit/s (the fastest eDVS line) carries about 600k events/s without timestamps.
#include <benchmark/benchmark.h>

#include "edvs/emulator.h"
#include "edvs/event_encoder.h"
#include "edvs/event_parser.h"

namespace {

void BM_Parse(benchmark::State& state) {
  const auto format = static_cast<edvs::EventFormat>(state.range(0));
  const ebslam::EventVector events = edvs::generateEvents(1, 200000, 200000);
  const std::vector<std::uint8_t> bytes = edvs::encodeEvents(events, format);
  edvs::ParserConfig cfg;
  cfg.format = format;
  edvs::EventParser parser(cfg);
  ebslam::EventVector out;
  out.reserve(events.size());
  std::int64_t host_us = 0;
  for (auto _ : state) {
    out.clear();
    parser.restart();
    for (std::size_t pos = 0; pos < bytes.size(); pos += 4096) {
      const std::size_t n = std::min<std::size_t>(4096, bytes.size() - pos);
      parser.feed(bytes.data() + pos, n, host_us, out);
      host_us += 10000;  // reads 10 ms apart: every step is plausible
    }
    parser.flush(out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) *
                          static_cast<std::int64_t>(events.size()));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) *
                          static_cast<std::int64_t>(bytes.size()));
  state.SetLabel(edvs::toString(format));
}

}  // namespace

BENCHMARK(BM_Parse)->DenseRange(0, 4)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();

// Event packet decoding throughput on one core, per encoding, on real recordings: the evt3
// (Prophesee 1280x720) and libcaer (DAVIS 640x480) excerpts of test/data/event_packets, and the
// libcaer events re-encoded as mono and libcaer_cmp. Reports events/s (items_per_second) and,
// side by side in the same process, the ratio to copying the decoded events (memory bound: the
// ceiling for any decoder writing the same output).
//   ebslam_event_packet_bench [--packets_dir=DIR] --benchmark_counters_tabular=true
// Targets: evt3 >= 100 M events/s, libcaer and mono >= 200 M events/s.

#include <benchmark/benchmark.h>

#include <time.h>
#include <cstring>
#include <string>
#include <vector>

#include "../test/event_packet_encoders.h"
#include "ebslam/events/event_packet.h"

namespace {

// Thread CPU time [s]: the machine may be shared, wall time would count other processes.
double secondsNow() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

std::string g_packets_dir = EBSLAM_BENCH_PACKETS_DIR;

struct Stream {
  ebslam::EventEncoding encoding;
  ebslam::SensorSize sensor;
  std::vector<ebslam::EventPacket> packets;
  std::size_t events = 0;
};

std::size_t decodeAll(const Stream& s, ebslam::PacketEventVector& out) {
  ebslam::EventPacketDecoder decoder(s.encoding, s.sensor);
  out.clear();
  for (const auto& p : s.packets)
    decoder.decode(p.events.data(), p.events.size(), p.time_base, out);
  return out.size();
}

Stream load(const std::string& file) {
  Stream s;
  s.packets = ebslam::readEventPacketFile(g_packets_dir + "/" + file);
  s.encoding = *ebslam::eventEncodingFromName(s.packets.front().encoding);
  s.sensor = {s.packets.front().width, s.packets.front().height};
  ebslam::PacketEventVector out;
  s.events = decodeAll(s, out);
  return s;
}

// The libcaer excerpt re-encoded packet by packet.
Stream reencode(const Stream& libcaer, ebslam::EventEncoding encoding) {
  Stream s = libcaer;
  s.encoding = encoding;
  ebslam::EventPacketDecoder decoder(libcaer.encoding, libcaer.sensor);
  for (auto& p : s.packets) {
    ebslam::PacketEventVector events;
    decoder.decode(p.events.data(), p.events.size(), p.time_base, events);
    p.time_base = events.front().t_ns;
    p.events = encoding == ebslam::EventEncoding::kMono
                   ? test_encoders::mono(events, p.time_base)
                   : test_encoders::libcaerCmp(events, p.time_base);
    p.encoding = ebslam::eventEncodingName(encoding);
  }
  return s;
}

const Stream& stream(ebslam::EventEncoding encoding) {
  static const Stream evt3 = load("evt3_prophesee_1280x720.evpk");
  static const Stream libcaer = load("libcaer_rollover_640x480.evpk");
  static const Stream mono = reencode(libcaer, ebslam::EventEncoding::kMono);
  static const Stream cmp = reencode(libcaer, ebslam::EventEncoding::kLibcaerCmp);
  switch (encoding) {
    case ebslam::EventEncoding::kEvt3:
      return evt3;
    case ebslam::EventEncoding::kLibcaer:
      return libcaer;
    case ebslam::EventEncoding::kMono:
      return mono;
    case ebslam::EventEncoding::kLibcaerCmp:
      return cmp;
  }
  return evt3;
}

// Nanoseconds per event of copying the decoded events (the ratio's denominator).
double copyNsPerEvent(const ebslam::PacketEventVector& events) {
  ebslam::PacketEventVector copy;
  copy.reserve(events.size());
  const int rounds = 20;
  const auto start = secondsNow();
  for (int r = 0; r < rounds; ++r) {
    copy.clear();
    copy.insert(copy.end(), events.begin(), events.end());
    benchmark::DoNotOptimize(copy.data());
    benchmark::ClobberMemory();
  }
  return (secondsNow() - start) * 1e9 /
         (static_cast<double>(rounds) * static_cast<double>(events.size()));
}

void BM_Decode(benchmark::State& state, ebslam::EventEncoding encoding) {
  const Stream& s = stream(encoding);
  ebslam::PacketEventVector out;
  out.reserve(s.events);
  std::size_t bytes = 0;
  for (const auto& p : s.packets) bytes += p.events.size();
  const auto start = secondsNow();
  for (auto _ : state) {
    benchmark::DoNotOptimize(decodeAll(s, out));
    benchmark::ClobberMemory();
  }
  const double decode_ns =
      (secondsNow() - start) * 1e9 /
      (static_cast<double>(state.iterations()) * static_cast<double>(s.events));
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * s.events));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * bytes));
  state.counters["events"] = static_cast<double>(s.events);
  state.counters["Mev_per_cpu_s"] = 1e3 / decode_ns;
  state.counters["bytes_per_event"] = static_cast<double>(bytes) / static_cast<double>(s.events);
  state.counters["decode_over_copy"] = decode_ns / copyNsPerEvent(out);
}

BENCHMARK_CAPTURE(BM_Decode, evt3, ebslam::EventEncoding::kEvt3);
BENCHMARK_CAPTURE(BM_Decode, libcaer, ebslam::EventEncoding::kLibcaer);
BENCHMARK_CAPTURE(BM_Decode, libcaer_cmp, ebslam::EventEncoding::kLibcaerCmp);
BENCHMARK_CAPTURE(BM_Decode, mono, ebslam::EventEncoding::kMono);

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--packets_dir=", 14) == 0) g_packets_dir = argv[i] + 14;
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

// End-to-end rate through the emulator: a pty eDVS streams N seeded events at a requested rate
// limited to the line rate (4 Mbit/s 8N1 = 400000 bytes/s by default); the device class reads
// and parses them. Prints events/s and the number of lost or altered events (must be 0).
//   edvs_throughput --events 400000 --rate 200000 --baud 4000000 --format E2
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>

#include "edvs_driver/device.h"
#include "edvs_driver/emulator.h"

int main(int argc, char** argv) {
  CLI::App app{"End-to-end eDVS throughput through the pty emulator"};
  std::size_t count = 400000;
  double rate = 200000;
  int baud = 4000000;
  std::string format = "E2";
  bool no_infer = false;
  app.add_option("--events", count, "number of events");
  app.add_option("--rate", rate, "generator rate [events/s] (capped by the line rate)");
  app.add_option("--baud", baud, "emulated line rate [bit/s]; 0 = unlimited");
  app.add_option("--format", format, "event format E0..E4");
  app.add_flag("--no-host-wraps", no_infer, "do not infer hidden wraps from host time");
  CLI11_PARSE(app, argc, argv);
  try {
    const auto f = edvs_driver::parseEventFormat(format, edvs_driver::Firmware::kCurrent);
    if (!f) throw std::invalid_argument("bad --format");
    edvs_driver::EmulatorConfig ec;
    ec.seed = 42;
    ec.rate_hz = rate;
    ec.max_events = count;
    ec.line_bytes_per_second = baud / 10.0;
    edvs_driver::Emulator emulator(ec);
    edvs_driver::DeviceConfig dc;
    dc.uri = emulator.uri();
    dc.format = *f;
    dc.command_gap_ms = 2;
    dc.infer_wraps_from_host_time = !no_infer;
    edvs_driver::EdvsDevice device(dc);
    device.open();
    ebslam::EventVector got;
    got.reserve(count);
    const auto start = std::chrono::steady_clock::now();
    device.start();
    auto last = start;
    while (got.size() < count &&
           std::chrono::steady_clock::now() - last < std::chrono::seconds(2)) {
      if (device.read(got, 20) > 0) last = std::chrono::steady_clock::now();
    }
    const double seconds = std::chrono::duration<double>(last - start).count();
    const ebslam::EventVector sent = emulator.sentEvents();
    std::size_t mismatched = 0;
    for (std::size_t i = 0; i < std::min(got.size(), sent.size()); ++i) {
      const bool same = got[i].x == sent[i].x && got[i].y == sent[i].y &&
                        got[i].polarity == sent[i].polarity &&
                        (*f == edvs_driver::EventFormat::kNone ||
                         got[i].t_us - got[0].t_us == sent[i].t_us - sent[0].t_us);
      if (!same && mismatched++ == 0) {
        std::printf("first altered event %zu: got t=%lld x=%u y=%u, sent t=%lld x=%u y=%u\n", i,
                    static_cast<long long>(got[i].t_us - got[0].t_us), got[i].x, got[i].y,
                    static_cast<long long>(sent[i].t_us - sent[0].t_us), sent[i].x, sent[i].y);
      }
    }
    const std::size_t lost = sent.size() > got.size() ? sent.size() - got.size() : 0;
    const double bytes = static_cast<double>(device.stats().bytes_read);
    std::printf(
        "format %s  line %d bit/s  events %zu/%zu  lost %zu  altered %zu  dropped bytes %lu\n",
        toString(*f), baud, got.size(), sent.size(), lost, mismatched,
        static_cast<unsigned long>(device.stats().parser.bytes_dropped));
    std::printf("wraps %lu (inferred from host time %lu)\n",
                static_cast<unsigned long>(device.stats().parser.wraps),
                static_cast<unsigned long>(device.stats().parser.wraps_from_host_time));
    std::printf("time %.3f s  rate %.0f events/s  %.0f bytes/s (%.2f Mbit/s 8N1)\n", seconds,
                got.size() / seconds, bytes / seconds, bytes * 10 / seconds / 1e6);
    return lost == 0 && mismatched == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "edvs_throughput: %s\n", e.what());
    return 2;
  }
}

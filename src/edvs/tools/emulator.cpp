// An emulated eDVS on a pseudo-terminal (or a loopback TCP port), for trying the driver without
// hardware:
//   edvs_emulator --link /tmp/edvs0 --rate 20000          # then uri:=serial:///tmp/edvs0
//   edvs_emulator --file events.txt --loop --link /tmp/edvs0
//   edvs_emulator --tcp 56000 --garbage 0.01              # then uri:=tcp://127.0.0.1:56000
#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <random>
#include <set>
#include <thread>

#include "ebslam/events/event_io.h"
#include "edvs/emulator.h"

namespace {
std::atomic<bool> g_stop{false};  // lock-free, so safe to set from the signal handler
void onSignal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Emulated eDVS4337 on a pseudo-terminal or TCP port"};
  edvs::EmulatorConfig config;
  std::string file, file_format, firmware = "current";
  int baud = 4000000;
  double duration_s = 0;
  std::size_t stall_after = 0, vanish_after = 0;
  app.add_option("--link", config.link_path, "symlink kept pointing at the pty (like /dev/edvs)");
  app.add_option("--tcp", config.tcp_port, "serve TCP on 127.0.0.1:PORT instead of a pty");
  app.add_option("--file", file, "stream the events of this file (binary, text, rpg)");
  app.add_option("--file-format", file_format,
                 "format of --file (binary, text, rpg); default: detect");
  app.add_flag("--loop", config.loop, "repeat the file");
  app.add_option("--speed", config.speed, "file playback speed (1 = real time)");
  app.add_option("--seed", config.seed, "generator seed");
  app.add_option("--rate", config.rate_hz, "generator rate [events/s]");
  app.add_option("--max-events", config.max_events, "stop streaming after N events (0 = never)");
  app.add_option("--firmware", firmware, "current or legacy (!E1..!E3 shifted)");
  app.add_option("--baud", baud, "emulated line rate [bit/s], 8N1; 0 = unlimited");
  app.add_option("--garbage", config.garbage_probability,
                 "probability per event of 1..8 random bytes");
  std::size_t cuts = 0;
  app.add_option("--cuts", cuts,
                 "cut this many random events in the middle (first 1..n-1 bytes sent; needs "
                 "--max-events or --file)");
  app.add_option("--stale-bytes", config.stale_bytes, "bytes of an old stream waiting at open");
  app.add_option("--stall-after", stall_after, "stall after N events...");
  app.add_option("--stall-ms", config.stall_ms, "...for this many milliseconds");
  app.add_option("--vanish-after", vanish_after, "close the device after N events...");
  app.add_option("--return-after-ms", config.return_after_ms,
                 "...and come back after this long (-1: never)");
  app.add_option("--duration", duration_s, "exit after this many seconds (0 = until Ctrl-C)");
  CLI11_PARSE(app, argc, argv);

  config.tcp = config.tcp_port > 0 || app.count("--tcp") > 0;
  config.line_bytes_per_second = baud / 10.0;
  if (stall_after > 0) config.stall_after_events = stall_after;
  if (vanish_after > 0) config.vanish_after_events = vanish_after;
  const auto fw = edvs::parseFirmware(firmware);
  if (!fw) {
    std::fprintf(stderr, "edvs_emulator: --firmware must be current or legacy\n");
    return 2;
  }
  config.firmware = *fw;
  try {
    if (!file.empty()) {
      std::optional<ebslam::EventFileFormat> format;
      if (!file_format.empty()) {
        format = ebslam::parseEventFileFormat(file_format);
        if (!format) throw std::invalid_argument("unknown --file-format " + file_format);
      }
      ebslam::EventReadResult read = ebslam::readEventFile(file, format);
      if (read.error)
        std::fprintf(stderr, "edvs_emulator: %s (using the events before it)\n",
                     read.error->c_str());
      ebslam::sortEventsByTime(read.events);
      std::size_t outside = 0;
      for (const ebslam::Event& e : read.events) {
        if (e.x < 128 && e.y < 128) {
          config.events.push_back(e);
        } else {
          ++outside;
        }
      }
      if (outside > 0) {
        std::fprintf(stderr, "edvs_emulator: %zu events outside 128x128 skipped\n", outside);
      }
      if (config.events.empty()) throw std::runtime_error("no events to stream in " + file);
    }
    if (cuts > 0) {
      const std::size_t total = config.max_events > 0 ? config.max_events : config.events.size();
      if (total < 2) throw std::invalid_argument("--cuts needs --max-events or --file");
      std::mt19937 rng(config.seed ^ 0x5bd1e995u);
      std::set<std::size_t> at;
      while (at.size() < std::min(cuts, total / 2)) at.insert(1 + rng() % (total - 1));
      config.cut_events.assign(at.begin(), at.end());
    }
    edvs::Emulator emulator(config);
    std::printf("edvs_emulator: device %s  (uri %s)\n", emulator.devicePath().c_str(),
                emulator.uri().c_str());
    std::fflush(stdout);
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    const auto start = std::chrono::steady_clock::now();
    while (!g_stop && (duration_s <= 0 || std::chrono::steady_clock::now() - start <
                                              std::chrono::duration<double>(duration_s))) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    std::printf("edvs_emulator: sent %zu events, %lu garbage bytes, %zu events cut\n",
                emulator.eventsSent(), static_cast<unsigned long>(emulator.garbageBytesSent()),
                emulator.eventsCut());
    for (const std::string& v : emulator.violations()) {
      std::printf("edvs_emulator: protocol violation: %s\n", v.c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "edvs_emulator: %s\n", e.what());
    return 1;
  }
  return 0;
}

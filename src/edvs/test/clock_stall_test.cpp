// The unwrapped device clock across gaps, on the emulated eDVS through a pseudo-terminal:
//   - a stalled line (the device keeps time and queues its events, then sends the backlog in a
//     burst at the line rate): the burst's own timestamps carry the device time that passed, so
//     no wrap period may be added from host time;
//   - a quiet device (no events at all for longer than a wrap period): the periods the gap hid
//     come from host time;
//   - a reader that stops reading for 200 ms (descheduled) right after it found the line idle.
// Required (E2 and E3, stalls of 0.1, 0.2, 1 and 3 s): 0 events lost or invented, final time
// error under 1 ms, time never backwards. Every result is printed.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <string>
#include <thread>

#include "edvs/device.h"
#include "edvs/emulator.h"
#include "edvs/recording_stream.h"
#include "edvs/stream_check.h"
#include "host_reads.h"

using ebslam::EventVector;
using edvs::DeviceConfig;
using edvs::EdvsDevice;
using edvs::Emulator;
using edvs::EmulatorConfig;
using edvs::EventFormat;

namespace {

DeviceConfig configFor(const Emulator& emulator, EventFormat format) {
  DeviceConfig c;
  c.uri = emulator.uri();
  c.format = format;
  c.command_gap_ms = 2;
  return c;
}

/// Reads until `count` events arrived or `timeout_ms` passed, then reads until the line is idle
/// (which releases the events held for confirmation). `pause_after` > 0: after that many events
/// and the next read that finds the line idle, the reader sleeps `pause_ms` without reading.
EventVector collect(EdvsDevice& device, std::size_t count, int timeout_ms,
                    std::size_t pause_after = 0, int pause_ms = 0, bool* paused = nullptr) {
  EventVector out;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  bool done_pause = pause_after == 0;
  while (out.size() < count && std::chrono::steady_clock::now() < deadline) {
    const std::uint64_t bytes = device.stats().bytes_read;
    device.read(out, 5);
    const bool idle = device.stats().bytes_read == bytes;
    if (!done_pause && out.size() >= pause_after && idle) {
      std::this_thread::sleep_for(std::chrono::milliseconds(pause_ms));
      done_pause = true;
    }
  }
  for (int i = 0; i < 3; ++i) device.read(out, 20);
  if (paused) *paused = done_pause;
  return out;
}

edvs::StreamComparison check(const char* what, EventFormat f, int gap_ms, const EventVector& sent,
                             const EventVector& got, const EdvsDevice& device) {
  const edvs::StreamComparison c =
      edvs::compareStreams(sent, got, true, edvs::wrapPeriodUs(f), 4096);
  const edvs::ParserStats& s = device.stats().parser;
  std::printf(
      "%s %s gap %d ms: sent %zu published %zu lost %zu invented %zu backwards %zu final error "
      "%lld us; wraps %llu (from host time %llu), gaps judged %llu; dropped bytes %llu rejected "
      "%llu clock jumps %llu\n",
      what, edvs::toString(f), gap_ms, c.sent, c.published, c.lost, c.invented, c.backwards,
      static_cast<long long>(c.final_error_us), static_cast<unsigned long long>(s.wraps),
      static_cast<unsigned long long>(s.wraps_from_host_time),
      static_cast<unsigned long long>(s.gaps_judged),
      static_cast<unsigned long long>(s.bytes_dropped),
      static_cast<unsigned long long>(s.rejected_events),
      static_cast<unsigned long long>(s.clock_jumps));
  EXPECT_EQ(c.lost, 0u);
  EXPECT_EQ(c.invented, 0u);
  EXPECT_EQ(c.backwards, 0u);
  EXPECT_LT(std::abs(c.final_error_us), 1000);
  return c;
}

constexpr EventFormat kFormats[] = {EventFormat::kAbs16, EventFormat::kAbs24};

}  // namespace

TEST(ClockStall, BurstAfterAStalledLineKeepsTheClock) {
  // 10 k events/s (E2: 40 kB/s on a 400 kB/s line): the backlog of a 3 s stall drains in about
  // 0.3 s, after which the stream is live again.
  for (EventFormat f : kFormats) {
    for (int stall_ms : {100, 200, 1000, 3000}) {
      SCOPED_TRACE(std::string(edvs::toString(f)) + " stall " + std::to_string(stall_ms));
      EmulatorConfig ec;
      ec.seed = static_cast<std::uint32_t>(17 + stall_ms);
      ec.rate_hz = 10000;
      ec.stall_after_events = 2000;
      ec.stall_ms = stall_ms;
      ec.max_events = 2000 + static_cast<std::size_t>(10.0 * (stall_ms + 400));
      Emulator emulator(ec);
      EdvsDevice device(configFor(emulator, f));
      device.open();
      device.start();
      const EventVector got = collect(device, ec.max_events, stall_ms + 5000);
      check("stall", f, stall_ms, emulator.sentEvents(), got, device);
      EXPECT_EQ(device.stats().parser.wraps_from_host_time, 0u);
    }
  }
}

namespace {

/// The repository's real recordings (test/data/event_packets: a DAVIS through libcaer and a
/// Prophesee in evt3) as eDVS streams at `rate_hz` on average.
ebslam::EventVector realStream(const std::string& file, double rate_hz) {
  ebslam::SensorSize sensor;
  const ebslam::EventVector raw = edvs::readRecording(
      std::string(EDVS_SAMPLE_SESSION_DIR) + "/../event_packets/" + file, sensor);
  return edvs::edvsStreamFromRecording(raw, sensor, rate_hz);
}

}  // namespace

TEST(ClockStall, DeviceHoldOfARealRecordingKeepsTheClock) {
  // A real recording at 40 k events/s (E2: 160 kB/s on a 400 kB/s line); the emulated device
  // holds its bytes for 300 ms (four and a half E2 periods) with its clock running, then sends
  // the backlog at once (a writer that held its bytes). Every event exact: the periods the host
  // clock saw during the hold were the backlog's. The backlog drained at the line rate and
  // holds of 3 s and 10 s: ParserReplayOfADeviceHoldOfRealRecordings (deterministic) and
  // edvs_hold_bench (through the pty).
  const struct {
    const char* file;
    bool at_line_rate;
  } cases[] = {{"evt3_prophesee_1280x720.evpk", false}};
  for (const auto& c : cases) {
    SCOPED_TRACE(std::string(c.file) + (c.at_line_rate ? " drained at the line rate" : " at once"));
    EmulatorConfig ec;
    ec.events = realStream(c.file, 40000.0);
    ec.events.resize(24000);  // 0.6 s
    ec.stall_after_events = 8000;
    ec.stall_ms = 300;
    ec.stall_drains_at_line_rate = c.at_line_rate;
    Emulator emulator(ec);
    EdvsDevice device(configFor(emulator, EventFormat::kAbs16));
    device.open();
    device.start();
    const EventVector got = collect(device, ec.events.size(), 5000);
    const edvs::StreamComparison cmp =
        check("hold", EventFormat::kAbs16, 300, emulator.sentEvents(), got, device);
    EXPECT_EQ(cmp.final_error_us, 0);
    EXPECT_EQ(cmp.sent, ec.events.size());
    EXPECT_EQ(device.stats().parser.wraps_from_host_time, 0u);
  }
}

TEST(ClockStall, QuietDeviceGapsAddTheHiddenPeriods) {
  // No events at all for 0.1..3 s between busy stretches: the host clock must supply the wrap
  // periods (E2: 1..45 of them), exactly.
  for (EventFormat f : kFormats) {
    for (int gap_ms : {100, 200, 1000, 3000}) {
      SCOPED_TRACE(std::string(edvs::toString(f)) + " quiet " + std::to_string(gap_ms));
      EventVector events =
          edvs::generateEvents(static_cast<std::uint32_t>(40 + gap_ms), 10000, 4000);
      // Second half shifted by the gap.
      for (std::size_t i = 2000; i < events.size(); ++i) events[i].t_us += gap_ms * 1000;
      EmulatorConfig ec;
      ec.events = events;
      Emulator emulator(ec);
      EdvsDevice device(configFor(emulator, f));
      device.open();
      device.start();
      const EventVector got = collect(device, events.size(), gap_ms + 5000);
      check("quiet", f, gap_ms, emulator.sentEvents(), got, device);
    }
  }
}

TEST(ClockStall, ReaderPausedFor200msChangesNothing) {
  // The reader finds the line idle in a short quiet stretch (20 ms, no period hidden), then is
  // descheduled for 200 ms (three E2 periods) while the device streams on; its next reads
  // drain the backlog.
  for (EventFormat f : kFormats) {
    SCOPED_TRACE(edvs::toString(f));
    EventVector events = edvs::generateEvents(91, 10000, 8000);
    for (std::size_t i = 2000; i < events.size(); ++i) events[i].t_us += 20000;
    EmulatorConfig ec;
    ec.events = events;
    Emulator emulator(ec);
    EdvsDevice device(configFor(emulator, f));
    device.open();
    device.start();
    bool paused = false;
    const EventVector got = collect(device, events.size(), 5000, 2000, 200, &paused);
    EXPECT_TRUE(paused) << "the reader never found the line idle";
    check("reader paused", f, 200, emulator.sentEvents(), got, device);
    EXPECT_EQ(device.stats().parser.wraps_from_host_time, 0u);
  }
}

namespace {

/// Parser-level replay: `events` leave the device in order; event i reaches the host at
/// arrival[i] (>= its device time + 1 ms); the host reads every 0.1..`max_read_gap_us` (up to
/// 4 KiB per read, as EdvsDevice), a read that finds nothing noting the idle line. A reader
/// paused from pause_at for pause_us does not read in between.
EventVector replay(const EventVector& events, const std::vector<std::int64_t>& arrival,
                   EventFormat f, std::uint32_t seed, edvs::ParserStats* stats,
                   std::int64_t pause_at = -1, std::int64_t pause_us = 0,
                   double line_bytes_per_s = 0.0) {
  std::vector<std::uint8_t> bytes;
  std::vector<std::int64_t> byte_arrival;
  for (std::size_t i = 0; i < events.size(); ++i) {
    const std::size_t before = bytes.size();
    edvs::encodeEvent(events[i], f, i > 0 ? events[i - 1].t_us : events[i].t_us, 1, bytes);
    byte_arrival.insert(byte_arrival.end(), bytes.size() - before, arrival[i]);
  }
  edvs::ParserConfig cfg;
  cfg.format = f;
  cfg.line_bytes_per_s = line_bytes_per_s;
  edvs::EventParser parser(cfg);
  std::mt19937 rng(seed);
  EventVector got;
  edvs_test::readAsHost(parser, bytes, byte_arrival, rng, 900, got, pause_at, pause_us);
  for (int i = 0; i < 2; ++i) {  // the line stays idle: two idle reads
    parser.noteIdle();
    parser.flush(got);
  }
  if (stats) *stats = parser.stats();
  return got;
}

/// Arrival times of a line that carries `line_bytes_per_s` and stalls from `stall_at` [us device
/// time] for `stall_us`: 1 ms latency, events queue while the line is stalled or busy.
std::vector<std::int64_t> lineArrival(const EventVector& events, EventFormat f,
                                      std::int64_t stall_at, std::int64_t stall_us,
                                      double line_bytes_per_s = 400000.0) {
  std::vector<std::int64_t> arrival;
  const double per_event_us = 1e6 * edvs::minEventBytes(f) / line_bytes_per_s;
  double line_free = 0;
  for (const auto& e : events) {
    double t = static_cast<double>(e.t_us) + 1000.0;
    if (e.t_us >= stall_at && e.t_us < stall_at + stall_us) {
      t = std::max(t, static_cast<double>(stall_at + stall_us) + 1000.0);
    }
    t = std::max(t, line_free);
    line_free = t + per_event_us;
    arrival.push_back(static_cast<std::int64_t>(t));
  }
  return arrival;
}

}  // namespace

TEST(ClockStall, ParserReplayOfStallsQuietGapsAndPauses) {
  // The same cases without a pty, deterministic: E2, E3, E4; 10 k events/s.
  for (EventFormat f : {EventFormat::kAbs16, EventFormat::kAbs24, EventFormat::kAbs32}) {
    for (int gap_ms : {100, 200, 1000, 3000}) {
      SCOPED_TRACE(std::string(edvs::toString(f)) + " gap " + std::to_string(gap_ms));
      const std::int64_t gap = gap_ms * 1000;
      const std::size_t n = 2000 + static_cast<std::size_t>(10 * (gap_ms + 400));
      const EventVector events = edvs::generateEvents(static_cast<std::uint32_t>(gap_ms), 1e4, n);
      const std::int64_t at = events[2000].t_us;
      edvs::ParserStats s;
      // Every replay must give the sent stream back exactly.
      const auto expectExact = [&](const char* what, const EventVector& sent,
                                   const EventVector& got) {
        const edvs::StreamComparison c =
            edvs::compareStreams(sent, got, true, edvs::wrapPeriodUs(f));
        std::printf(
            "replay %s %s %d ms: lost %zu invented %zu backwards %zu final error %lld us "
            "(dropped bytes %llu, wraps from host time %llu)\n",
            what, edvs::toString(f), gap_ms, c.lost, c.invented, c.backwards,
            static_cast<long long>(c.final_error_us),
            static_cast<unsigned long long>(s.bytes_dropped),
            static_cast<unsigned long long>(s.wraps_from_host_time));
        EXPECT_EQ(c.lost + c.invented + c.backwards, 0u) << what;
        EXPECT_EQ(c.final_error_us, 0) << what;
      };
      // Stalled line.
      expectExact("stall", events, replay(events, lineArrival(events, f, at, gap), f, 5, &s));
      // Quiet device: the second part shifted by the gap.
      EventVector quiet = events;
      for (std::size_t i = 2000; i < quiet.size(); ++i) quiet[i].t_us += gap;
      expectExact("quiet", quiet, replay(quiet, lineArrival(quiet, f, 0, 0), f, 6, &s));
      // Reader paused for gap_ms right after a 20 ms quiet stretch.
      EventVector pause = events;
      for (std::size_t i = 2000; i < pause.size(); ++i) pause[i].t_us += 20000;
      expectExact(
          "pause", pause,
          replay(pause, lineArrival(pause, f, 0, 0), f, 7, &s, pause[1999].t_us + 8000, gap));
    }
  }
}

TEST(ClockStall, ParserReplayOfADeviceHoldOfRealRecordings) {
  // The repository's real DAVIS and Prophesee recordings at 40 k events/s, E2, on a 400 kB/s
  // line that the device holds for 3 s, then drains at the line rate (2 s); the parser knows
  // the line rate. Every event exact, no period from host time (edvs_hold_bench: 10 s).
  const struct {
    const char* file;
    int hold_ms;
  } cases[] = {{"libcaer_rollover_640x480.evpk", 3000}, {"evt3_prophesee_1280x720.evpk", 3000}};
  for (const auto& c : cases) {
    SCOPED_TRACE(std::string(c.file) + " hold " + std::to_string(c.hold_ms) + " ms");
    const EventVector once = realStream(c.file, 40000.0);
    // Repeated (1 ms apart) over the hold, its drain and 0.5 s before and after.
    const std::int64_t span = 1000LL * (500 + c.hold_ms + c.hold_ms * 2 / 3 + 500);
    EventVector events;
    for (std::int64_t offset = 0; events.empty() || events.back().t_us < span;
         offset = events.back().t_us + 1000) {
      for (ebslam::Event e : once) {
        e.t_us += offset;
        events.push_back(e);
      }
    }
    const EventFormat f = EventFormat::kAbs16;
    edvs::ParserStats s;
    const EventVector got = replay(events, lineArrival(events, f, 500000, 1000LL * c.hold_ms), f,
                                   31, &s, -1, 0, 400000.0);
    const edvs::StreamComparison cmp = edvs::compareStreams(events, got, true, 65536);
    std::printf(
        "replay hold %s %d ms: sent %zu published %zu lost %zu invented %zu final error %lld us "
        "(wraps from host time %llu, gaps judged %llu)\n",
        c.file, c.hold_ms, cmp.sent, cmp.published, cmp.lost, cmp.invented,
        static_cast<long long>(cmp.final_error_us),
        static_cast<unsigned long long>(s.wraps_from_host_time),
        static_cast<unsigned long long>(s.gaps_judged));
    EXPECT_EQ(cmp.lost + cmp.invented + cmp.backwards, 0u);
    EXPECT_EQ(cmp.final_error_us, 0);
    EXPECT_EQ(s.wraps_from_host_time, 0u);
  }
}

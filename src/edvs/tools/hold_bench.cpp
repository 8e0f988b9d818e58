// Device-side hold: an emulated eDVS on a pseudo-terminal streams a real recording, holds its
// bytes for a while (its clock runs on, its events queue) and then sends the backlog, at once
// or drained at the line rate; EdvsDevice reads and unwraps the stream. Prints, per recording
// and hold: events sent and published, the final time error, how many events are more than
// 1 ms off and the largest error, and the wrap periods taken from host time. Exit status 1
// unless every run has final error 0 us and no event more than 1 ms off.
//   edvs_hold_bench --hold-ms 3000 --hold-ms 10000 --rate 40000 --format E2
// Recordings (any number of --recording; default: shapes_rotation and dynamic_translation of
// ../shared/data/rpg-events, else the repository's test/data/event_packets excerpts) are
// subsampled onto 128 x 128 and retimed to --rate events/s on average (edvs/recording_stream.h),
// repeated as needed to cover the run.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "edvs/device.h"
#include "edvs/emulator.h"
#include "edvs/recording_stream.h"
#include "edvs/stream_check.h"

namespace {

struct HoldResult {
  std::size_t sent = 0;
  std::size_t published = 0;
  std::size_t lost = 0;
  std::size_t invented = 0;
  std::int64_t final_error_us = 0;
  std::size_t off_1ms = 0;
  std::int64_t max_error_us = 0;
  std::uint64_t wraps_from_host = 0;
  std::uint64_t gaps_judged = 0;
  std::int64_t first_off_us = -1;  // device time of the first event > 1 ms off (from the start)
};

// The recording repeated (1 ms apart) until it spans at least span_us.
ebslam::EventVector repeatTo(const ebslam::EventVector& once, std::int64_t span_us) {
  ebslam::EventVector out;
  std::int64_t offset = 0;
  while (out.empty() || out.back().t_us < span_us) {
    for (ebslam::Event e : once) {
      e.t_us += offset;
      out.push_back(e);
    }
    offset = out.back().t_us + 1000;
  }
  return out;
}

HoldResult runHold(const ebslam::EventVector& stream, edvs::EventFormat format, int before_ms,
                   int hold_ms, int after_ms, bool at_line_rate, double line_bytes_per_s) {
  edvs::EmulatorConfig ec;
  ec.events = repeatTo(stream, 1000LL * (before_ms + 2 * hold_ms + after_ms));
  std::size_t stall_after = 0;
  while (stall_after < ec.events.size() && ec.events[stall_after].t_us < 1000LL * before_ms) {
    ++stall_after;
  }
  ec.stall_after_events = std::max<std::size_t>(1, stall_after);
  ec.stall_ms = hold_ms;
  ec.stall_drains_at_line_rate = at_line_rate;
  ec.line_bytes_per_second = line_bytes_per_s;
  edvs::Emulator emulator(ec);
  edvs::DeviceConfig dc;
  dc.uri = emulator.uri() + "?baud=" + std::to_string(static_cast<long>(line_bytes_per_s * 10));
  dc.format = format;
  dc.command_gap_ms = 2;
  edvs::EdvsDevice device(dc);
  device.open();
  ebslam::EventVector got;
  got.reserve(ec.events.size());
  device.start();
  // Until the whole recording went out and the line stayed idle for longer than the hold.
  auto last = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - last < std::chrono::milliseconds(hold_ms + 500)) {
    const std::uint64_t before = device.stats().bytes_read;
    device.read(got, 20);
    if (device.stats().bytes_read != before) last = std::chrono::steady_clock::now();
  }
  const ebslam::EventVector sent = emulator.sentEvents();
  const edvs::StreamComparison c =
      edvs::compareStreams(sent, got, true, edvs::wrapPeriodUs(format), 4096);
  HoldResult r;
  r.sent = c.sent;
  r.published = c.published;
  r.lost = c.lost;
  r.invented = c.invented;
  r.final_error_us = c.final_error_us;
  r.wraps_from_host = device.stats().parser.wraps_from_host_time;
  r.gaps_judged = device.stats().parser.gaps_judged;
  // Per event: without noise the published stream is the sent one, in order.
  const std::size_t n = std::min(sent.size(), got.size());
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t err = (got[i].t_us - got[0].t_us) - (sent[i].t_us - sent[0].t_us);
    if (std::llabs(err) > 1000 && r.off_1ms++ == 0) r.first_off_us = sent[i].t_us - sent[0].t_us;
    r.max_error_us = std::max<std::int64_t>(r.max_error_us, std::llabs(err));
  }
  r.off_1ms += sent.size() > n ? sent.size() - n : got.size() - n;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Device-side hold of an emulated eDVS streaming real recordings"};
  std::vector<std::string> recordings;
  std::vector<int> holds;
  double rate = 40000;
  std::string format_name = "E2";
  int before_ms = 1000;
  int after_ms = 1500;
  double baud = 4000000;
  std::string release = "both";
  app.add_option("--recording", recordings, "real recording (.evpk or event file); repeatable");
  app.add_option("--hold-ms", holds, "hold length [ms]; repeatable (default 3000 and 10000)");
  app.add_option("--rate", rate, "mean event rate the recordings are retimed to [events/s]");
  app.add_option("--format", format_name, "event format E2..E4");
  app.add_option("--before-ms", before_ms, "stream before the hold [ms]");
  app.add_option("--after-ms", after_ms, "stream after the backlog could have drained [ms]");
  app.add_option("--baud", baud, "line rate [bit/s] (8N1: baud / 10 bytes/s)");
  app.add_option("--release", release, "backlog sent 'at-once', at the 'line-rate', or 'both'");
  CLI11_PARSE(app, argc, argv);
  try {
    const auto format = edvs::parseEventFormat(format_name, edvs::Firmware::kCurrent);
    if (!format || edvs::wrapPeriodUs(*format) == 0) {
      throw std::invalid_argument("--format must be E2, E3 or E4");
    }
    if (holds.empty()) holds = {3000, 10000};
    if (recordings.empty()) {
      const std::string shared = std::string(EDVS_REPO_ROOT) + "/../shared/data/rpg-events/";
      if (std::ifstream(shared + "shapes_rotation/events.txt")) {
        recordings = {shared + "shapes_rotation/events.txt",
                      shared + "dynamic_translation/events.txt"};
      } else {
        const std::string packets = std::string(EDVS_REPO_ROOT) + "/test/data/event_packets/";
        recordings = {packets + "libcaer_rollover_640x480.evpk",
                      packets + "evt3_prophesee_1280x720.evpk"};
      }
    }
    std::vector<bool> modes;
    if (release != "line-rate") modes.push_back(false);
    if (release != "at-once") modes.push_back(true);
    bool ok = true;
    for (const std::string& path : recordings) {
      ebslam::SensorSize sensor;
      const ebslam::EventVector raw = edvs::readRecording(path, sensor);
      const ebslam::EventVector stream = edvs::edvsStreamFromRecording(raw, sensor, rate);
      for (int hold : holds) {
        for (bool at_line_rate : modes) {
          const HoldResult r =
              runHold(stream, *format, before_ms, hold, after_ms, at_line_rate, baud / 10);
          const bool exact =
              r.final_error_us == 0 && r.off_1ms == 0 && r.lost == 0 && r.invented == 0;
          ok = ok && exact;
          std::printf(
              "%s %s %.0f ev/s hold %d ms backlog %s: sent %zu published %zu lost %zu invented "
              "%zu final error %lld us, %zu events > 1 ms off (%.1f %%), max error %lld us, first "
              "at %.3f s; "
              "wraps from host time %llu, gaps judged %llu: %s\n",
              path.substr(path.find_last_of('/', path.size() - 12) + 1).c_str(),
              edvs::toString(*format), rate, hold, at_line_rate ? "at the line rate" : "at once",
              r.sent, r.published, r.lost, r.invented, static_cast<long long>(r.final_error_us),
              r.off_1ms, r.sent ? 100.0 * r.off_1ms / r.sent : 0.0,
              static_cast<long long>(r.max_error_us), r.first_off_us * 1e-6,
              static_cast<unsigned long long>(r.wraps_from_host),
              static_cast<unsigned long long>(r.gaps_judged), exact ? "exact" : "NOT exact");
          std::fflush(stdout);
        }
      }
    }
    std::printf("final error 0 us and no event > 1 ms off in every run: %s\n", ok ? "yes" : "NO");
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "edvs_hold_bench: %s\n", e.what());
    return 2;
  }
}

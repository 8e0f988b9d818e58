#pragma once
// The host's side of a serial line in the eDVS tests: reads at random intervals of the bytes that
// have arrived by then, as EdvsDevice reads them.

#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "edvs/event_parser.h"

namespace edvs_test {

/// Feeds `bytes` (byte i arrives at host time `arrival[i]` [us], non-decreasing) to `parser` as a
/// host that reads every 100 + (rng() % `step_spread_us`) us, up to 4 KiB per read (as
/// EdvsDevice), each read taking the bytes that arrived by then; a read that finds nothing notes
/// the idle line and flushes. From host time `pause_at` [us] (if >= 0) the host does not read for
/// `pause_us` (a descheduled reader). Appends the parsed events to `got`.
inline void readAsHost(edvs::EventParser& parser, const std::vector<std::uint8_t>& bytes,
                       const std::vector<std::int64_t>& arrival, std::mt19937& rng,
                       std::uint32_t step_spread_us, ebslam::EventVector& got,
                       std::int64_t pause_at = -1, std::int64_t pause_us = 0) {
  std::size_t pos = 0;
  std::int64_t host = arrival.front();
  bool paused = false;
  while (pos < bytes.size()) {
    host += 100 + static_cast<std::int64_t>(rng() % step_spread_us);
    if (!paused && pause_at >= 0 && host >= pause_at) {
      host += pause_us;
      paused = true;
    }
    std::size_t end = pos;
    while (end < bytes.size() && end - pos < 4096 && arrival[end] <= host) ++end;
    if (end == pos) {
      parser.noteIdle();
      parser.flush(got);
      continue;
    }
    parser.feed(bytes.data() + pos, end - pos, host, got);
    pos = end;
  }
}

}  // namespace edvs_test

#pragma once
// Encoders for the event packet tests and benchmarks (the library only decodes): `mono` and
// `libcaer_cmp` bytes of decoded events, written from the formats as documented in
// docs/event_file_format.md#event-camera-encodings (libcaer_cmp: libcaer_driver's compression
// tokens, code << 12 | payload, vectors of 8 rows).

#include <cstdint>
#include <vector>

#include "ebslam/events/event_packet.h"

namespace test_encoders {

inline void putWord(std::vector<std::uint8_t>& out, int code, int payload) {
  const auto w = static_cast<std::uint16_t>((code << 12) | (payload & 0xFFF));
  out.push_back(static_cast<std::uint8_t>(w & 0xFF));
  out.push_back(static_cast<std::uint8_t>(w >> 8));
}

/// libcaer_cmp bytes of events (in time order, at most 16.7 s after base_ns) of one packet whose
/// time_base is base_ns.
inline std::vector<std::uint8_t> libcaerCmp(const ebslam::PacketEventVector& events,
                                            std::uint64_t base_ns) {
  std::vector<std::uint8_t> out;
  std::uint64_t high = ~0ull, low = ~0ull;
  int x = -1;
  std::size_t i = 0;
  while (i < events.size()) {
    const ebslam::PacketEvent& e = events[i];
    const std::uint64_t dt = (e.t_ns - base_ns) / 1000;
    if ((dt >> 12) != high) {
      high = dt >> 12;
      putWord(out, 0, static_cast<int>(high));
    }
    if ((dt & 0xFFF) != low) {
      low = dt & 0xFFF;
      putWord(out, 1, static_cast<int>(low));
    }
    if (e.x != x) {
      x = e.x;
      putWord(out, 2, x);
    }
    // A run of events at one time, column and polarity within one 8-row block: one vector.
    std::size_t j = i + 1;
    int mask = 1 << (e.y & 7);
    while (j < events.size() && events[j].t_ns == e.t_ns && events[j].x == e.x &&
           events[j].polarity == e.polarity && (events[j].y & ~7) == (e.y & ~7) &&
           !(mask & (1 << (events[j].y & 7)))) {
      mask |= 1 << (events[j].y & 7);
      ++j;
    }
    if (j - i == 1) {
      putWord(out, 3, (e.polarity ? 0x800 : 0) | e.y);
    } else {
      putWord(out, 4, (e.polarity ? 0x800 : 0) | (e.y & ~7));
      putWord(out, 5, mask);
    }
    i = j;
  }
  return out;
}

/// mono bytes of events at most 4.29 s after base_ns (time_base = base_ns).
inline std::vector<std::uint8_t> mono(const ebslam::PacketEventVector& events,
                                      std::uint64_t base_ns) {
  std::vector<std::uint8_t> out;
  out.reserve(8 * events.size());
  for (const ebslam::PacketEvent& e : events) {
    const std::uint64_t w = ((e.t_ns - base_ns) & 0xFFFFFFFFull) | std::uint64_t{e.x} << 32 |
                            std::uint64_t{e.y} << 48 | std::uint64_t{e.polarity} << 63;
    for (int b = 0; b < 8; ++b) out.push_back(static_cast<std::uint8_t>(w >> (8 * b)));
  }
  return out;
}

}  // namespace test_encoders

#pragma once
// Shared body of the per-encoding libFuzzer targets of EventPacketDecoder (fuzz_evt3_decoder,
// fuzz_libcaer_decoder, fuzz_libcaer_cmp_decoder, fuzz_mono_decoder): any bytes must decode
// without crashing, reading out of bounds or undefined behaviour, and the promises hold: every
// event inside the sensor, the counts add up, and (evt3, mono: state spans packets) a stream cut
// at a word boundary decodes to the same events as in one piece.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "ebslam/events/event_packet.h"

namespace fuzz_packets {

inline bool same(const ebslam::PacketEventVector& a, const ebslam::PacketEventVector& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].t_ns != b[i].t_ns || a[i].x != b[i].x || a[i].y != b[i].y ||
        a[i].polarity != b[i].polarity) {
      return false;
    }
  }
  return true;
}

inline int run(ebslam::EventEncoding encoding, const std::uint8_t* data, std::size_t size) {
  if (size < 4) return 0;
  // First 4 bytes: sensor width and height (1..256 each: small, so that `outside` is hit).
  const ebslam::SensorSize sensor{1u + data[0], 1u + data[1]};
  const std::uint64_t time_base = std::uint64_t{data[2]} << 40 | data[3];
  data += 4;
  size -= 4;
  ebslam::EventPacketDecoder whole(encoding, sensor);
  ebslam::PacketEventVector events;
  std::vector<ebslam::TriggerEvent> triggers;
  const ebslam::PacketDecodeStats s = whole.decode(data, size, time_base, events, &triggers);
  if (s.events != events.size() || s.triggers != triggers.size()) std::abort();
  for (const auto& e : events) {
    if (e.x >= sensor.width || e.y >= sensor.height) std::abort();
  }
  const std::size_t word =
      encoding == ebslam::EventEncoding::kLibcaer || encoding == ebslam::EventEncoding::kMono ? 8
                                                                                              : 2;
  if (s.dropped_bytes < size % word || s.dropped_bytes > size) std::abort();
  if (word == 8 && s.events + s.outside != size / 8) std::abort();
  if (encoding == ebslam::EventEncoding::kEvt3 || encoding == ebslam::EventEncoding::kMono) {
    const std::size_t cut = (size / 2 / word) * word;
    ebslam::EventPacketDecoder split(encoding, sensor);
    ebslam::PacketEventVector parts;
    // evt3 drops words before its first time stamp per packet: start both with one.
    const std::uint8_t time[4] = {0x00, 0x80, 0x00, 0x60};  // TIME_HIGH 0, TIME_LOW 0
    ebslam::PacketEventVector w2, p2;
    if (encoding == ebslam::EventEncoding::kEvt3) {
      ebslam::EventPacketDecoder w(encoding, sensor);
      w.decode(time, 4, 0, w2);
      w.decode(data, size, 0, w2);
      split.decode(time, 4, 0, p2);
      split.decode(data, cut, 0, p2);
      split.decode(data + cut, size - cut, 0, p2);
      if (!same(w2, p2)) std::abort();
    } else {
      split.decode(data, cut, time_base, parts);
      split.decode(data + cut, size - cut, time_base, parts);
      if (!same(events, parts)) std::abort();
    }
  }
  return 0;
}

}  // namespace fuzz_packets

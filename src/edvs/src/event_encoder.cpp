#include "edvs/event_encoder.h"
#include <stdexcept>

namespace edvs {

void encodeEvent(const ebslam::Event& event, EventFormat format, std::int64_t previous_us,
                 int on_bit, std::vector<std::uint8_t>& out) {
  if (event.x > 127 || event.y > 127) {
    throw std::invalid_argument("eDVS event coordinates must be 0..127");
  }
  const int p = event.polarity ? on_bit : 1 - on_bit;
  out.push_back(static_cast<std::uint8_t>(0x80 | event.y));
  out.push_back(static_cast<std::uint8_t>((p << 7) | event.x));
  switch (format) {
    case EventFormat::kNone:
      return;
    case EventFormat::kDelta: {
      const std::int64_t delta = event.t_us - previous_us;
      if (delta < 0) throw std::invalid_argument("event times must not run backwards");
      if (delta >= (std::int64_t{1} << 28)) {
        throw std::invalid_argument("delta timestamp does not fit in 4 x 7 bits");
      }
      int groups = 1;
      while (groups < 4 && (delta >> (7 * groups)) != 0) ++groups;
      for (int g = groups - 1; g >= 0; --g) {
        auto byte = static_cast<std::uint8_t>((delta >> (7 * g)) & 0x7F);
        if (g == 0) byte |= 0x80;
        out.push_back(byte);
      }
      return;
    }
    case EventFormat::kAbs16:
    case EventFormat::kAbs24:
    case EventFormat::kAbs32: {
      const int n = timestampBytes(format);
      const std::uint64_t t = static_cast<std::uint64_t>(event.t_us);
      for (int k = n - 1; k >= 0; --k) out.push_back(static_cast<std::uint8_t>(t >> (8 * k)));
      return;
    }
  }
}

std::vector<std::uint8_t> encodeEvents(const ebslam::EventVector& events, EventFormat format,
                                       int on_bit) {
  std::vector<std::uint8_t> out;
  out.reserve(events.size() * static_cast<std::size_t>(2 + timestampBytes(format)));
  std::int64_t previous = events.empty() ? 0 : events.front().t_us;
  for (const ebslam::Event& e : events) {
    encodeEvent(e, format, previous, on_bit, out);
    previous = e.t_us;
  }
  return out;
}

}  // namespace edvs

// libFuzzer target: arbitrary bytes, split into arbitrary reads, in every format. Checks the
// parser's promises: no crash, coordinates inside the sensor, time never running backwards,
// byte accounting consistent.
#include <cstdint>
#include <cstdlib>

#include "edvs/event_parser.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const auto format = static_cast<edvs::EventFormat>(data[0] % 5);
  const std::size_t chunk = 1 + data[1] % 64;
  data += 2;
  size -= 2;
  edvs::ParserConfig cfg;
  cfg.format = format;
  edvs::EventParser parser(cfg);
  ebslam::EventVector out;
  std::int64_t host = 0;
  for (std::size_t pos = 0; pos < size; pos += chunk) {
    const std::size_t n = std::min(chunk, size - pos);
    parser.feed(data + pos, n, host, out);
    host += (data[pos] & 0x0F) * 1000;
  }
  parser.flush(out);
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (out[i].x >= 128 || out[i].y >= 128) std::abort();
    if (i > 0 && out[i].t_us < out[i - 1].t_us) std::abort();
  }
  const auto& s = parser.stats();
  if (s.bytes_in != size || s.bytes_dropped > s.bytes_in) std::abort();
  // Fixed-size formats: every byte was published in an event, dropped, or is still pending.
  const int frame = edvs::minEventBytes(format);
  if (format != edvs::EventFormat::kDelta &&
      s.events * static_cast<std::uint64_t>(frame) + s.bytes_dropped + parser.pendingBytes() !=
          s.bytes_in) {
    std::abort();
  }
  return 0;
}

#include "edvs/format_detection.h"
#include "edvs/event_parser.h"

namespace edvs {

FormatGuess guessEventFormat(const std::vector<std::uint8_t>& bytes) {
  FormatGuess best;
  bool have = false;
  for (EventFormat f : kAllEventFormats) {
    ParserConfig cfg;
    cfg.format = f;
    EventParser parser(cfg);
    ebslam::EventVector events;
    parser.feed(bytes, std::nullopt, events);
    parser.flush(events);
    const ParserStats& s = parser.stats();
    const double drop = s.bytes_in ? static_cast<double>(s.bytes_dropped) / s.bytes_in : 1.0;
    const double jump = s.events ? static_cast<double>(s.implausible_jumps) / s.events : 1.0;
    const double score = drop + jump;
    // Formats are tried in order of increasing timestamp information; "<=" hands a tie to the
    // richer format.
    if (s.events > 0 && (!have || score <= best.score + 1e-12)) {
      best = FormatGuess{f, score, s.events};
      have = true;
    }
  }
  return best;
}

}  // namespace edvs

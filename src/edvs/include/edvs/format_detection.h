#pragma once

// Guessing the event format of a captured byte stream (to check it against the announced one).

#include <cstdint>
#include <vector>

#include "edvs/event_format.h"

namespace edvs {

/// Result of guessing the format of a captured byte stream.
struct FormatGuess {
  EventFormat format = EventFormat::kNone;
  double score = 0.0;  ///< fraction of dropped bytes plus fraction of implausible jumps
  std::uint64_t events = 0;
};

/// Parses `bytes` (without host times) with every format and returns the one that explains
/// them best: fewest dropped bytes and implausible timestamp jumps; ties go to the format with
/// more timestamp information. Used to check a stream against the announced format.
FormatGuess guessEventFormat(const std::vector<std::uint8_t>& bytes);

}  // namespace edvs

#pragma once

// Scoring a decoded event stream against the stream that was sent: lost and invented events,
// how far the decoded clock ran ahead of the true one, time running backwards. Used by the
// property tests, edvs_throughput and the rostest. ROS-free.

#include <cstddef>
#include <cstdint>

#include "ebslam/events/event.h"

namespace edvs {

struct StreamComparison {
  std::size_t sent = 0;       ///< events of the true stream
  std::size_t published = 0;  ///< events decoded
  std::size_t matched = 0;    ///< decoded events equal to a true event, in order
  std::size_t lost = 0;       ///< true events without a decoded match
  std::size_t invented = 0;   ///< decoded events without a true match
  /// Invented events whose pixel lies outside the bounding box of the true stream's pixels.
  std::size_t invented_outside_pixels = 0;
  std::size_t backwards = 0;  ///< decoded steps back in time
  /// Most a decoded time exceeded the time of the next true event still to come [us]
  /// (<= 0: never ahead of the stream; a matched event counts 0). Only with times compared.
  std::int64_t max_ahead_us = 0;
  /// Time of the last decoded event minus that of the last true event [us] (offset removed).
  std::int64_t final_error_us = 0;
  std::int64_t offset_us = 0;  ///< decoded minus true time, found from the first match

  double lostShare() const { return sent ? static_cast<double>(lost) / sent : 0.0; }
  double inventedShare() const { return sent ? static_cast<double>(invented) / sent : 0.0; }
};

/// Aligns `decoded` with `sent` in order: a decoded event matches the next true event with the
/// same pixel and polarity within `window` events and, if `compare_times`, the same time after
/// removing a constant offset (decoded minus sent, taken from the first event whose pixel,
/// polarity and time modulo `period_us` agree with one of the first `window` true events;
/// period_us 0 = no wrap). The true times must not run backwards.
StreamComparison compareStreams(const ebslam::EventVector& sent, const ebslam::EventVector& decoded,
                                bool compare_times, std::int64_t period_us = 0,
                                std::size_t window = 4096);

}  // namespace edvs

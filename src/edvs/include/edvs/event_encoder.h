#pragma once

// The device side of the event formats: events to bytes (used by the emulator and tests).

#include <cstdint>
#include <vector>

#include "ebslam/events/event.h"
#include "edvs/event_format.h"

namespace edvs {

/// Encodes events in `format` (the device side, used by the emulator and tests). For the
/// absolute formats the times are taken modulo the wrap period; for kDelta the difference to
/// the previous event (the first relative to `previous_us`) must fit in 28 bits.
/// Throws std::invalid_argument for a coordinate above 127, a time running backwards or a delta
/// too large.
void encodeEvent(const ebslam::Event& event, EventFormat format, std::int64_t previous_us,
                 int on_bit, std::vector<std::uint8_t>& out);
std::vector<std::uint8_t> encodeEvents(const ebslam::EventVector& events, EventFormat format,
                                       int on_bit = 1);

}  // namespace edvs

#pragma once

// eDVS4337 event formats on the wire: their names, the `!En` command numbers of both firmware
// generations and the bytes of one event. One event: 1yyyyyyy pxxxxxxx, then the format's time
// field (none, 1-4 delta bytes, or a big-endian 16/24/32-bit device time in us); p = 1 is ON
// (ParserConfig::on_bit swaps it). Byte layouts, wrap periods and the polarity convention:
// edvs_driver/README.md, "Event formats and robustness" and "Polarity convention".

#include <cstdint>
#include <optional>
#include <string_view>

namespace edvs {

/// What follows the two address bytes of an event on the wire.
enum class EventFormat { kNone, kDelta, kAbs16, kAbs24, kAbs32 };

/// Firmware generation. Older firmware numbers the timestamp formats one lower:
///   current: !E0 none, !E1 delta, !E2 16 bit, !E3 24 bit, !E4 32 bit
///   legacy:  !E0 none, !E1 16 bit, !E2 24 bit, !E3 32 bit (no delta format)
enum class Firmware { kCurrent, kLegacy };

/// All five formats, in command-number order of the current firmware.
inline constexpr EventFormat kAllEventFormats[] = {EventFormat::kNone, EventFormat::kDelta,
                                                   EventFormat::kAbs16, EventFormat::kAbs24,
                                                   EventFormat::kAbs32};

/// Short name: "none", "delta", "ts16", "ts24", "ts32".
const char* toString(EventFormat format);
const char* toString(Firmware firmware);
/// Parses "current"/"legacy"; std::nullopt otherwise.
std::optional<Firmware> parseFirmware(std::string_view name);

/// Parses a format given either as the command the firmware understands ("E0".."E4", also
/// "!E2", "2") interpreted for `firmware`, or as a name ("none", "delta", "ts16", "ts24",
/// "ts32"). Returns std::nullopt for anything else and for a number the firmware does not have.
std::optional<EventFormat> parseEventFormat(std::string_view text, Firmware firmware);

/// The number n of the `!En` command that selects `format` on `firmware`.
/// Throws std::invalid_argument for kDelta on legacy firmware (it has no such format).
int formatCommandNumber(EventFormat format, Firmware firmware);

/// The format that `!En` selects on `firmware`; std::nullopt for an unknown n.
std::optional<EventFormat> formatFromCommandNumber(int n, Firmware firmware);

/// Number of timestamp bytes after the address bytes (kDelta: the maximum, 4).
int timestampBytes(EventFormat format);
/// Wrap period of an absolute timestamp format [us]; 0 for kNone and kDelta.
std::int64_t wrapPeriodUs(EventFormat format);
/// Bytes of one event on the wire (kDelta: the minimum, 3).
int minEventBytes(EventFormat format);

}  // namespace edvs

#include "edvs/event_format.h"
#include <stdexcept>
#include <string>

#include "lowercase.h"

namespace edvs {

using detail::lower;

const char* toString(EventFormat format) {
  switch (format) {
    case EventFormat::kNone:
      return "none";
    case EventFormat::kDelta:
      return "delta";
    case EventFormat::kAbs16:
      return "ts16";
    case EventFormat::kAbs24:
      return "ts24";
    case EventFormat::kAbs32:
      return "ts32";
  }
  return "?";
}

const char* toString(Firmware firmware) {
  return firmware == Firmware::kLegacy ? "legacy" : "current";
}

std::optional<Firmware> parseFirmware(std::string_view name) {
  const std::string n = lower(name);
  if (n == "current" || n == "new") return Firmware::kCurrent;
  if (n == "legacy" || n == "old") return Firmware::kLegacy;
  return std::nullopt;
}

std::optional<EventFormat> parseEventFormat(std::string_view text, Firmware firmware) {
  std::string t = lower(text);
  for (EventFormat f : kAllEventFormats) {
    if (t == toString(f)) return f;
  }
  if (!t.empty() && t[0] == '!') t.erase(0, 1);
  if (!t.empty() && t[0] == 'e') t.erase(0, 1);
  if (t.size() != 1 || t[0] < '0' || t[0] > '9') return std::nullopt;
  return formatFromCommandNumber(t[0] - '0', firmware);
}

int formatCommandNumber(EventFormat format, Firmware firmware) {
  const int current = static_cast<int>(format);  // enum order is the current numbering
  if (firmware == Firmware::kCurrent) return current;
  if (format == EventFormat::kDelta) {
    throw std::invalid_argument("legacy eDVS firmware has no delta-timestamp event format");
  }
  return format == EventFormat::kNone ? 0 : current - 1;
}

std::optional<EventFormat> formatFromCommandNumber(int n, Firmware firmware) {
  if (firmware == Firmware::kCurrent) {
    if (n < 0 || n > 4) return std::nullopt;
    return static_cast<EventFormat>(n);
  }
  if (n < 0 || n > 3) return std::nullopt;
  return n == 0 ? EventFormat::kNone : static_cast<EventFormat>(n + 1);
}

int timestampBytes(EventFormat format) {
  switch (format) {
    case EventFormat::kNone:
      return 0;
    case EventFormat::kDelta:
      return 4;
    case EventFormat::kAbs16:
      return 2;
    case EventFormat::kAbs24:
      return 3;
    case EventFormat::kAbs32:
      return 4;
  }
  return 0;
}

std::int64_t wrapPeriodUs(EventFormat format) {
  switch (format) {
    case EventFormat::kAbs16:
      return std::int64_t{1} << 16;
    case EventFormat::kAbs24:
      return std::int64_t{1} << 24;
    case EventFormat::kAbs32:
      return std::int64_t{1} << 32;
    case EventFormat::kNone:
    case EventFormat::kDelta:
      break;
  }
  return 0;
}

int minEventBytes(EventFormat format) {
  return format == EventFormat::kDelta ? 3 : 2 + timestampBytes(format);
}

}  // namespace edvs

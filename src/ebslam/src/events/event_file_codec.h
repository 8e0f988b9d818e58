#pragma once

// Internal to the event file reader and writer (event_io.cpp, event_file_writer.cpp): the binary
// format's constants, CRC-32, little-endian helpers, text parsing and format detection.
// Format: docs/event_file_format.md

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "ebslam/events/event_io.h"

namespace ebslam {

// ---- binary format constants (docs/event_file_format.md) ----
constexpr char kFileMagic[8] = {'E', 'B', 'S', 'L', 'A', 'M', 'E', 'V'};
constexpr std::uint16_t kFormatVersion = 1;
constexpr std::size_t kFileHeaderBytes = 32;
constexpr char kBlockMagic[4] = {'E', 'V', 'B', 'K'};
constexpr char kEndMagic[4] = {'E', 'V', 'N', 'D'};  // end marker, block-header sized
constexpr std::size_t kBlockHeaderBytes = 24;
constexpr std::size_t kRecordBytes = 8;
constexpr std::uint32_t kMaxBlockEvents = 65536;    // readers accept up to this many
constexpr std::uint32_t kWriterBlockEvents = 4096;  // writers use this (32 KiB of records)
constexpr std::uint32_t kMaxBinaryWidth = 65535;
constexpr std::uint32_t kMaxBinaryHeight = 32768;  // y keeps 15 bits, bit 15 is polarity
constexpr std::uint16_t kPolarityBit = 0x8000;

// The Event Camera Dataset was recorded with a DAVIS240C.
constexpr SensorSize kRpgSensor{240, 180};

constexpr const char* kTextHeaderPrefix = "# ebslam events text v1";
constexpr std::size_t kMaxTextLine = 1024;  // longer lines are garbage, not events

// ---- CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320, as zlib) ----
inline std::array<std::uint32_t, 256> makeCrcTable() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}

inline std::uint32_t crc32(const std::uint8_t* data, std::size_t size) {
  static const std::array<std::uint32_t, 256> table = makeCrcTable();
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < size; ++i) c = table[(c ^ data[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

// ---- little-endian helpers (explicit, independent of the host byte order) ----
inline std::uint16_t getU16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
inline std::uint32_t getU32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
inline std::uint64_t getU64(const std::uint8_t* p) {
  return static_cast<std::uint64_t>(getU32(p)) | (static_cast<std::uint64_t>(getU32(p + 4)) << 32);
}
inline void putU16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
inline void putU32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline void putU64(std::uint8_t* p, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

inline std::string sensorText(const SensorSize& s) {
  return std::to_string(s.width) + "x" + std::to_string(s.height);
}

inline void checkBinarySensor(const SensorSize& sensor) {
  if (sensor.width == 0 || sensor.height == 0 || sensor.width > kMaxBinaryWidth ||
      sensor.height > kMaxBinaryHeight) {
    throw std::invalid_argument("binary event file: sensor size " + sensorText(sensor) +
                                " not representable (1..65535 x 1..32768)");
  }
}

// Reads up to `size` bytes; returns how many were read (less only at end of stream).
inline std::size_t readBytes(std::istream& in, std::uint8_t* data, std::size_t size) {
  in.read(reinterpret_cast<char*>(data), static_cast<std::streamsize>(size));
  return static_cast<std::size_t>(in.gcount());
}

// ---- text parsing ----
inline bool isSeparator(char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r'; }

// Splits `line` into whitespace/comma separated tokens; false if more than `max_tokens`.
inline std::size_t tokenize(const char* line, std::size_t length,
                            std::array<std::string_view, 5>& out) {
  std::size_t count = 0;
  std::size_t i = 0;
  while (i < length) {
    while (i < length && isSeparator(line[i])) ++i;
    if (i >= length) break;
    const std::size_t start = i;
    while (i < length && !isSeparator(line[i])) ++i;
    if (count == out.size()) return count + 1;
    out[count++] = std::string_view(line + start, i - start);
  }
  return count;
}

template <typename Integer>
inline bool parseInteger(std::string_view token, Integer& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size();
}

// Decimal seconds ("49.012157999", "-0.5", "1e-3") to microseconds, rounded to nearest.
// Plain decimals are converted exactly (no floating point), so 10^9-second Unix times keep
// microsecond precision.
inline bool parseSecondsToMicroseconds(std::string_view token, std::int64_t& t_us) {
  if (token.find_first_of("eE") != std::string_view::npos) {
    std::string copy(token);
    char* end = nullptr;
    const double seconds = std::strtod(copy.c_str(), &end);
    if (end != copy.c_str() + copy.size() || !std::isfinite(seconds)) return false;
    const double micros = std::round(seconds * 1e6);
    if (std::abs(micros) > 9.0e18) return false;
    t_us = static_cast<std::int64_t>(micros);
    return true;
  }
  bool negative = false;
  if (!token.empty() && (token.front() == '-' || token.front() == '+')) {
    negative = token.front() == '-';
    token.remove_prefix(1);
  }
  const std::size_t dot = token.find('.');
  std::string_view integer_part = token.substr(0, dot);
  std::string_view fraction =
      dot == std::string_view::npos ? std::string_view() : token.substr(dot + 1);
  if (integer_part.empty() && fraction.empty()) return false;
  // Magnitude in unsigned microseconds with overflow checks, so the whole int64 range
  // (including -2^63 us, which the writers emit as "-9223372036854.775808") round-trips.
  std::uint64_t seconds = 0;
  if (!integer_part.empty()) {
    for (char c : integer_part) {
      if (c < '0' || c > '9') return false;
    }
    if (!parseInteger(integer_part, seconds)) return false;
  }
  for (char c : fraction) {
    if (c < '0' || c > '9') return false;
  }
  std::uint64_t micros = 0;
  for (std::size_t i = 0; i < 6; ++i) {
    micros = micros * 10 + static_cast<std::uint64_t>(i < fraction.size() ? fraction[i] - '0' : 0);
  }
  if (fraction.size() > 6 && fraction[6] >= '5') ++micros;  // round half up
  constexpr std::uint64_t kLimit = std::uint64_t{1} << 63;  // |int64 min|
  if (seconds > kLimit / 1000000) return false;
  const std::uint64_t magnitude = seconds * 1000000 + micros;
  if (magnitude > kLimit || (!negative && magnitude == kLimit)) return false;
  t_us = negative ? static_cast<std::int64_t>(0 - magnitude) : static_cast<std::int64_t>(magnitude);
  return true;
}

enum class LineParse { kEvent, kSkip, kBad };

struct TextLineResult {
  LineParse kind = LineParse::kSkip;
  Event event;
  std::string problem;
};

inline TextLineResult parseTextLine(const char* line, std::size_t length, bool seconds_only) {
  TextLineResult result;
  std::size_t first = 0;
  while (first < length && isSeparator(line[first])) ++first;
  if (first == length || line[first] == '#') return result;  // blank or comment
  std::array<std::string_view, 5> tokens;
  const std::size_t count = tokenize(line, length, tokens);
  result.kind = LineParse::kBad;
  if (count != 4) {
    result.problem = "expected 4 fields 't x y p', found " +
                     (count > 4 ? std::string("more than 4") : std::to_string(count));
    return result;
  }
  const std::string_view t = tokens[0];
  const bool decimal = t.find_first_of(".eE") != std::string_view::npos;
  bool time_ok = false;
  if (decimal || seconds_only) {
    time_ok = parseSecondsToMicroseconds(t, result.event.t_us);
  } else {
    time_ok = parseInteger(t, result.event.t_us);
  }
  if (!time_ok) {
    result.problem = "bad timestamp '" + std::string(t) + "'";
    return result;
  }
  if (!parseInteger(tokens[1], result.event.x) || !parseInteger(tokens[2], result.event.y)) {
    result.problem =
        "bad pixel coordinates '" + std::string(tokens[1]) + " " + std::string(tokens[2]) + "'";
    return result;
  }
  const std::string_view p = tokens[3];
  if (p == "1" || p == "+1") {
    result.event.polarity = true;
  } else if (p == "0" || p == "-1") {
    result.event.polarity = false;
  } else {
    result.problem = "bad polarity '" + std::string(p) + "' (expected 1, 0 or -1)";
    return result;
  }
  result.kind = LineParse::kEvent;
  return result;
}

// Parses "# ebslam events text v1 width=W height=H"; nullopt if the line is not that header.
inline std::optional<SensorSize> parseTextHeader(const std::string& line) {
  if (line.rfind(kTextHeaderPrefix, 0) != 0) return std::nullopt;
  SensorSize sensor;
  std::istringstream fields(line.substr(std::strlen(kTextHeaderPrefix)));
  std::string field;
  bool has_width = false;
  bool has_height = false;
  while (fields >> field) {
    const auto eq = field.find('=');
    if (eq == std::string::npos) continue;
    std::uint32_t value = 0;
    if (!parseInteger(std::string_view(field).substr(eq + 1), value) || value == 0) continue;
    if (field.compare(0, eq, "width") == 0) {
      sensor.width = value;
      has_width = true;
    } else if (field.compare(0, eq, "height") == 0) {
      sensor.height = value;
      has_height = true;
    }
  }
  if (!has_width || !has_height) return std::nullopt;
  return sensor;
}

inline std::string directoryOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string(".") : path.substr(0, slash);
}

// Principal point (cx, cy) from an Event Camera Dataset calib.txt, if readable.
inline std::optional<std::pair<double, double>> readCalibPrincipalPoint(const std::string& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  if (!(in >> fx >> fy >> cx >> cy)) return std::nullopt;
  if (!std::isfinite(cx) || !std::isfinite(cy)) return std::nullopt;
  return std::make_pair(cx, cy);
}

inline EventFileFormat detectFromPrefix(const std::string& prefix) {
  if (!prefix.empty()) {
    const std::size_t n = std::min(prefix.size(), sizeof(kFileMagic));
    if (std::memcmp(prefix.data(), kFileMagic, n) == 0) return EventFileFormat::kBinary;
  }
  std::istringstream lines(prefix);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind(kTextHeaderPrefix, 0) == 0) return EventFileFormat::kText;
    const auto first = line.find_first_not_of(" \t\r,");
    if (first == std::string::npos || line[first] == '#') continue;
    const auto end = line.find_first_of(" \t\r,", first);
    const std::string token = line.substr(first, end == std::string::npos ? end : end - first);
    return token.find('.') != std::string::npos ? EventFileFormat::kRpgText
                                                : EventFileFormat::kText;
  }
  return EventFileFormat::kText;
}

inline std::string readPrefix(std::istream& in, std::size_t max_bytes) {
  std::string prefix(max_bytes, '\0');
  in.read(prefix.data(), static_cast<std::streamsize>(max_bytes));
  prefix.resize(static_cast<std::size_t>(in.gcount()));
  in.clear();
  in.seekg(0);
  return prefix;
}

constexpr std::size_t kDetectBytes = 4096;

}  // namespace ebslam

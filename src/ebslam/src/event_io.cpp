#include "ebslam/event_io.h"

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

namespace ebslam {
namespace {

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
std::array<std::uint32_t, 256> makeCrcTable() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}

std::uint32_t crc32(const std::uint8_t* data, std::size_t size) {
  static const std::array<std::uint32_t, 256> table = makeCrcTable();
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < size; ++i) c = table[(c ^ data[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

// ---- little-endian helpers (explicit, independent of the host byte order) ----
std::uint16_t getU16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
std::uint32_t getU32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
std::uint64_t getU64(const std::uint8_t* p) {
  return static_cast<std::uint64_t>(getU32(p)) | (static_cast<std::uint64_t>(getU32(p + 4)) << 32);
}
void putU16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
void putU32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void putU64(std::uint8_t* p, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

std::string sensorText(const SensorSize& s) {
  return std::to_string(s.width) + "x" + std::to_string(s.height);
}

void checkBinarySensor(const SensorSize& sensor) {
  if (sensor.width == 0 || sensor.height == 0 || sensor.width > kMaxBinaryWidth ||
      sensor.height > kMaxBinaryHeight) {
    throw std::invalid_argument("binary event file: sensor size " + sensorText(sensor) +
                                " not representable (1..65535 x 1..32768)");
  }
}

// Reads up to `size` bytes; returns how many were read (less only at end of stream).
std::size_t readBytes(std::istream& in, std::uint8_t* data, std::size_t size) {
  in.read(reinterpret_cast<char*>(data), static_cast<std::streamsize>(size));
  return static_cast<std::size_t>(in.gcount());
}

// ---- text parsing ----
bool isSeparator(char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r'; }

// Splits `line` into whitespace/comma separated tokens; false if more than `max_tokens`.
std::size_t tokenize(const char* line, std::size_t length, std::array<std::string_view, 5>& out) {
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
bool parseInteger(std::string_view token, Integer& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size();
}

// Decimal seconds ("49.012157999", "-0.5", "1e-3") to microseconds, rounded to nearest.
// Plain decimals are converted exactly (no floating point), so 10^9-second Unix times keep
// microsecond precision.
bool parseSecondsToMicroseconds(std::string_view token, std::int64_t& t_us) {
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

TextLineResult parseTextLine(const char* line, std::size_t length, bool seconds_only) {
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
std::optional<SensorSize> parseTextHeader(const std::string& line) {
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

std::string directoryOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string(".") : path.substr(0, slash);
}

// Principal point (cx, cy) from an Event Camera Dataset calib.txt, if readable.
std::optional<std::pair<double, double>> readCalibPrincipalPoint(const std::string& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  if (!(in >> fx >> fy >> cx >> cy)) return std::nullopt;
  if (!std::isfinite(cx) || !std::isfinite(cy)) return std::nullopt;
  return std::make_pair(cx, cy);
}

EventFileFormat detectFromPrefix(const std::string& prefix) {
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

std::string readPrefix(std::istream& in, std::size_t max_bytes) {
  std::string prefix(max_bytes, '\0');
  in.read(prefix.data(), static_cast<std::streamsize>(max_bytes));
  prefix.resize(static_cast<std::size_t>(in.gcount()));
  in.clear();
  in.seekg(0);
  return prefix;
}

constexpr std::size_t kDetectBytes = 4096;

}  // namespace

const char* toString(EventFileFormat format) {
  switch (format) {
    case EventFileFormat::kBinary:
      return "binary";
    case EventFileFormat::kText:
      return "text";
    case EventFileFormat::kRpgText:
      return "rpg";
  }
  return "unknown";
}

std::optional<EventFileFormat> parseEventFileFormat(const std::string& name) {
  if (name == "binary" || name == "bin" || name == "ebe") return EventFileFormat::kBinary;
  if (name == "text" || name == "txt") return EventFileFormat::kText;
  if (name == "rpg" || name == "rpg-text" || name == "ecd") return EventFileFormat::kRpgText;
  return std::nullopt;
}

EventFileFormat detectEventFileFormat(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open event file '" + path + "'");
  return detectFromPrefix(readPrefix(in, kDetectBytes));
}

EventFileFormat eventFileFormatFromExtension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const auto slash = path.find_last_of('/');
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash) &&
      path.substr(dot) == ".txt") {
    return EventFileFormat::kText;
  }
  return EventFileFormat::kBinary;
}

void sortEventsByTime(EventVector& events) {
  std::stable_sort(events.begin(), events.end(),
                   [](const Event& a, const Event& b) { return a.t_us < b.t_us; });
}

// ======================================================================================
// Reader
// ======================================================================================

struct EventFileReader::Impl {
  std::unique_ptr<std::istream> in;
  EventFileFormat format = EventFileFormat::kBinary;
  SensorSize sensor;
  bool sensor_known = true;  // false: text without declared size, sensor = bounding box
  bool done = false;
  std::optional<std::string> error;
  std::size_t events_read = 0;
  std::size_t non_monotonic = 0;
  std::optional<std::size_t> first_non_monotonic;
  std::optional<std::int64_t> last_t;

  // binary state
  std::uint64_t offset = 0;  // bytes consumed so far, for messages
  std::size_t block_index = 0;
  std::vector<std::uint8_t> block_buffer;
  EventVector pending;
  std::size_t pending_pos = 0;

  // text state
  std::size_t line_number = 0;
  std::array<char, kMaxTextLine + 2> line{};
  bool header_allowed = true;  // kText header only before the first event

  void fail(std::string message) {
    error = std::move(message);
    done = true;
  }

  void account(const Event& e) {
    if (last_t && e.t_us < *last_t) {
      if (!first_non_monotonic) first_non_monotonic = events_read;
      ++non_monotonic;
    }
    last_t = e.t_us;
    ++events_read;
  }

  void open(const EventReadOptions& options, const std::string& path_hint) {
    if (options.format) {
      format = *options.format;
    } else {
      format = detectFromPrefix(readPrefix(*in, kDetectBytes));
    }
    switch (format) {
      case EventFileFormat::kBinary:
        readFileHeader();
        break;
      case EventFileFormat::kText:
        if (options.sensor) {
          sensor = *options.sensor;
        } else {
          sensor = SensorSize{0, 0};
          sensor_known = false;
        }
        break;
      case EventFileFormat::kRpgText:
        sensor = kRpgSensor;
        if (options.sensor) {
          sensor = *options.sensor;
        } else if (!path_hint.empty()) {
          const auto pp = readCalibPrincipalPoint(directoryOf(path_hint) + "/calib.txt");
          if (pp && !(pp->first >= 0 && pp->first < kRpgSensor.width && pp->second >= 0 &&
                      pp->second < kRpgSensor.height)) {
            sensor = SensorSize{0, 0};
            sensor_known = false;
          }
        }
        break;
    }
  }

  void readFileHeader() {
    std::uint8_t header[kFileHeaderBytes];
    const std::size_t got = readBytes(*in, header, kFileHeaderBytes);
    offset += got;
    const std::size_t magic_bytes = std::min(got, sizeof(kFileMagic));
    if (std::memcmp(header, kFileMagic, magic_bytes) != 0) {
      fail("not an ebslam binary event file (bad magic)");
      return;
    }
    if (got < kFileHeaderBytes) {
      fail("truncated file header: " + std::to_string(got) + " of " +
           std::to_string(kFileHeaderBytes) + " bytes");
      return;
    }
    const std::uint16_t version = getU16(header + 8);
    const std::uint16_t header_bytes = getU16(header + 10);
    if (getU32(header + 28) != crc32(header, 28)) {
      fail("corrupt file header (CRC mismatch)");
      return;
    }
    if (version != kFormatVersion) {
      fail("unsupported binary event file version " + std::to_string(version) +
           " (this reader knows version " + std::to_string(kFormatVersion) + ")");
      return;
    }
    if (header_bytes != kFileHeaderBytes) {
      fail("corrupt file header: header size " + std::to_string(header_bytes));
      return;
    }
    sensor.width = getU32(header + 12);
    sensor.height = getU32(header + 16);
    if (sensor.width == 0 || sensor.height == 0 || sensor.width > kMaxBinaryWidth ||
        sensor.height > kMaxBinaryHeight) {
      fail("corrupt file header: sensor size " + sensorText(sensor));
      return;
    }
  }

  // Decodes the next block into `pending`. Sets done/error at the end or on damage.
  void readBlock() {
    pending.clear();
    pending_pos = 0;
    std::uint8_t header[kBlockHeaderBytes];
    const std::uint64_t block_offset = offset;
    const std::size_t got = readBytes(*in, header, kBlockHeaderBytes);
    offset += got;
    const std::string where =
        "block " + std::to_string(block_index) + " at byte " + std::to_string(block_offset);
    if (got == 0) {
      fail("truncated file: ends after " + std::to_string(events_read) +
           " events without the end marker (cut short, or the writer was not closed)");
      return;
    }
    if (got < kBlockHeaderBytes) {
      fail("truncated file: " + where + ": header has " + std::to_string(got) + " of " +
           std::to_string(kBlockHeaderBytes) + " bytes");
      return;
    }
    const bool end_marker = std::memcmp(header, kEndMagic, 4) == 0;
    if (!end_marker && std::memcmp(header, kBlockMagic, 4) != 0) {
      fail("corrupt file: " + where + ": bad block magic");
      return;
    }
    if (getU32(header + 20) != crc32(header, 20)) {
      fail("corrupt file: " + where + ": block header CRC mismatch");
      return;
    }
    if (end_marker) {
      const std::uint64_t total = getU64(header + 8);
      if (total != events_read) {
        fail("corrupt file: end marker counts " + std::to_string(total) + " events, read " +
             std::to_string(events_read));
      } else if (in->peek() != std::char_traits<char>::eof()) {
        fail("corrupt file: data after the end marker at byte " + std::to_string(offset));
      } else {
        done = true;  // clean end
      }
      return;
    }
    const std::uint32_t count = getU32(header + 4);
    if (count == 0 || count > kMaxBlockEvents) {
      fail("corrupt file: " + where + ": event count " + std::to_string(count));
      return;
    }
    const auto base_t = static_cast<std::int64_t>(getU64(header + 8));
    const std::uint32_t payload_crc = getU32(header + 16);
    block_buffer.resize(std::size_t{count} * kRecordBytes);
    const std::size_t payload = readBytes(*in, block_buffer.data(), block_buffer.size());
    offset += payload;
    const bool truncated = payload < block_buffer.size();
    if (!truncated && crc32(block_buffer.data(), payload) != payload_crc) {
      fail("corrupt file: " + where + ": event data CRC mismatch, its " + std::to_string(count) +
           " events dropped");
      return;
    }
    const std::size_t complete = payload / kRecordBytes;
    pending.reserve(complete);
    for (std::size_t i = 0; i < complete; ++i) {
      const std::uint8_t* r = block_buffer.data() + i * kRecordBytes;
      const auto dt = static_cast<std::int32_t>(getU32(r));
      Event e;
      e.x = getU16(r + 4);
      const std::uint16_t y_pol = getU16(r + 6);
      e.y = static_cast<std::uint16_t>(y_pol & ~kPolarityBit);
      e.polarity = (y_pol & kPolarityBit) != 0;
      // Base and offset are both read from disk: guard the sum against overflow.
      if ((dt > 0 && base_t > std::numeric_limits<std::int64_t>::max() - dt) ||
          (dt < 0 && base_t < std::numeric_limits<std::int64_t>::min() - dt)) {
        fail("corrupt file: " + where + ": timestamp overflow at event " + std::to_string(i));
        return;
      }
      e.t_us = base_t + dt;
      if (!sensor.contains(e)) {
        fail("corrupt file: " + where + ": event " + std::to_string(i) + " at (" +
             std::to_string(e.x) + ", " + std::to_string(e.y) + ") outside the " +
             sensorText(sensor) + " sensor");
        return;
      }
      pending.push_back(e);
    }
    ++block_index;
    if (truncated) {
      fail("truncated file: " + where + " declares " + std::to_string(count) +
           " events, file ends after " + std::to_string(complete) + " complete ones");
    }
  }

  std::size_t nextBinary(EventVector& batch, std::size_t max_events) {
    while (batch.size() < max_events) {
      if (pending_pos == pending.size()) {
        if (done) break;
        readBlock();
        if (pending.empty()) continue;  // end or damage (done is set) or nothing decoded
      }
      const std::size_t take = std::min(max_events - batch.size(), pending.size() - pending_pos);
      for (std::size_t i = 0; i < take; ++i) {
        const Event& e = pending[pending_pos + i];
        account(e);
        batch.push_back(e);
      }
      pending_pos += take;
    }
    return batch.size();
  }

  // Reads the next line into `line`; returns its length, or nullopt at end of input.
  // Sets the error for over-long lines.
  std::optional<std::size_t> nextLine() {
    in->getline(line.data(), static_cast<std::streamsize>(line.size()));
    const auto count = static_cast<std::size_t>(in->gcount());
    if (in->bad()) {
      fail("read error at line " + std::to_string(line_number + 1));
      return std::nullopt;
    }
    if (in->fail()) {
      if (count == 0 && in->eof()) return std::nullopt;  // nothing left
      // failbit with characters read: the line did not fit into the buffer.
      ++line_number;
      fail("line " + std::to_string(line_number) + ": longer than " + std::to_string(kMaxTextLine) +
           " characters (garbage?)");
      return std::nullopt;
    }
    ++line_number;
    // gcount includes the extracted '\n' unless the line ended at end of file.
    const bool had_newline = !in->eof();
    return had_newline ? count - 1 : count;
  }

  std::size_t nextText(EventVector& batch, std::size_t max_events) {
    const bool seconds_only = format == EventFileFormat::kRpgText;
    while (batch.size() < max_events && !done) {
      const auto length = nextLine();
      if (!length) {
        done = true;
        break;
      }
      if (std::memchr(line.data(), '\0', *length) != nullptr) {
        fail("line " + std::to_string(line_number) + ": binary data in a text event file");
        break;
      }
      if (header_allowed && format == EventFileFormat::kText && *length > 0 && line[0] == '#') {
        if (const auto declared = parseTextHeader(std::string(line.data(), *length))) {
          if (!sensor_known) {
            sensor = *declared;
            sensor_known = true;
          }
        }
        continue;
      }
      const TextLineResult parsed = parseTextLine(line.data(), *length, seconds_only);
      if (parsed.kind == LineParse::kSkip) continue;
      if (parsed.kind == LineParse::kBad) {
        fail("line " + std::to_string(line_number) + ": " + parsed.problem);
        break;
      }
      header_allowed = false;
      const Event& e = parsed.event;
      if (sensor_known) {
        if (!sensor.contains(e)) {
          fail("line " + std::to_string(line_number) + ": event at (" + std::to_string(e.x) + ", " +
               std::to_string(e.y) + ") outside the " + sensorText(sensor) + " sensor");
          break;
        }
      } else {
        sensor.width = std::max<std::uint32_t>(sensor.width, e.x + 1u);
        sensor.height = std::max<std::uint32_t>(sensor.height, e.y + 1u);
      }
      account(e);
      batch.push_back(e);
    }
    return batch.size();
  }
};

EventFileReader::EventFileReader(const std::string& path, const EventReadOptions& options)
    : impl_(std::make_unique<Impl>()) {
  auto file = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!*file) throw std::runtime_error("cannot open event file '" + path + "'");
  impl_->in = std::move(file);
  impl_->open(options, path);
}

EventFileReader::EventFileReader(std::unique_ptr<std::istream> stream,
                                 const EventReadOptions& options)
    : impl_(std::make_unique<Impl>()) {
  if (!stream || !*stream) throw std::runtime_error("EventFileReader: stream is not readable");
  impl_->in = std::move(stream);
  impl_->open(options, std::string());
}

EventFileReader::~EventFileReader() = default;
EventFileReader::EventFileReader(EventFileReader&&) noexcept = default;
EventFileReader& EventFileReader::operator=(EventFileReader&&) noexcept = default;

std::size_t EventFileReader::next(EventVector& batch, std::size_t max_events) {
  batch.clear();
  if (done() || max_events == 0) return 0;
  if (impl_->format == EventFileFormat::kBinary) return impl_->nextBinary(batch, max_events);
  return impl_->nextText(batch, max_events);
}

EventFileFormat EventFileReader::format() const { return impl_->format; }
SensorSize EventFileReader::sensor() const { return impl_->sensor; }
bool EventFileReader::done() const {
  return impl_->done && impl_->pending_pos == impl_->pending.size();
}
const std::optional<std::string>& EventFileReader::error() const { return impl_->error; }
std::size_t EventFileReader::eventsRead() const { return impl_->events_read; }
std::size_t EventFileReader::nonMonotonicCount() const { return impl_->non_monotonic; }
std::optional<std::size_t> EventFileReader::firstNonMonotonicIndex() const {
  return impl_->first_non_monotonic;
}

EventReadResult readEventFile(const std::string& path, std::optional<EventFileFormat> format) {
  EventReadOptions options;
  options.format = format;
  return readEventFile(path, options);
}

EventReadResult readEventFile(const std::string& path, const EventReadOptions& options) {
  EventFileReader reader(path, options);
  EventReadResult result;
  std::error_code ec;
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (!ec) {
    // Binary: an upper bound of the count (8 bytes per event). Text: a typical line has 16 to
    // 20 characters; a short guess only costs a regrowth.
    const std::uintmax_t bytes_per_event = reader.format() == EventFileFormat::kBinary ? 8 : 16;
    result.events.reserve(static_cast<std::size_t>(
        std::min<std::uintmax_t>(bytes / bytes_per_event, std::uintmax_t{1} << 28)));
  }
  EventVector batch;
  constexpr std::size_t kBatch = 1 << 16;
  while (reader.next(batch, kBatch) > 0) {
    result.events.insert(result.events.end(), batch.begin(), batch.end());
  }
  result.sensor = reader.sensor();
  result.error = reader.error();
  result.non_monotonic = reader.nonMonotonicCount();
  result.first_non_monotonic_index = reader.firstNonMonotonicIndex();
  return result;
}

// ======================================================================================
// Writer
// ======================================================================================

struct EventFileWriter::Impl {
  std::ofstream out;
  std::string path;
  EventFileFormat format = EventFileFormat::kBinary;
  SensorSize sensor;
  bool closed = false;
  std::size_t written = 0;
  // binary: records of the open block
  std::vector<std::uint8_t> records;
  std::uint32_t block_count = 0;
  std::int64_t block_base = 0;
  // text: formatted lines not yet handed to the stream
  std::string text;

  void checkStream() {
    if (!out) throw std::runtime_error("error writing event file '" + path + "'");
  }

  void writeHeader() {
    if (format == EventFileFormat::kBinary) {
      std::uint8_t header[kFileHeaderBytes] = {};
      std::memcpy(header, kFileMagic, sizeof(kFileMagic));
      putU16(header + 8, kFormatVersion);
      putU16(header + 10, static_cast<std::uint16_t>(kFileHeaderBytes));
      putU32(header + 12, sensor.width);
      putU32(header + 16, sensor.height);
      putU32(header + 20, 0);  // flags, none defined in version 1
      putU32(header + 24, 0);  // reserved
      putU32(header + 28, crc32(header, 28));
      out.write(reinterpret_cast<const char*>(header), kFileHeaderBytes);
    } else if (format == EventFileFormat::kText) {
      out << kTextHeaderPrefix << " width=" << sensor.width << " height=" << sensor.height
          << "\n# t[us] x y p(1=ON,0=OFF)\n";
    }
    checkStream();
  }

  void writeEndMarker() {
    std::uint8_t header[kBlockHeaderBytes] = {};
    std::memcpy(header, kEndMagic, 4);
    putU64(header + 8, static_cast<std::uint64_t>(written));
    putU32(header + 20, crc32(header, 20));
    out.write(reinterpret_cast<const char*>(header), kBlockHeaderBytes);
  }

  void flushBlock() {
    if (block_count == 0) return;
    std::uint8_t header[kBlockHeaderBytes];
    std::memcpy(header, kBlockMagic, 4);
    putU32(header + 4, block_count);
    putU64(header + 8, static_cast<std::uint64_t>(block_base));
    putU32(header + 16, crc32(records.data(), records.size()));
    putU32(header + 20, crc32(header, 20));
    out.write(reinterpret_cast<const char*>(header), kBlockHeaderBytes);
    out.write(reinterpret_cast<const char*>(records.data()),
              static_cast<std::streamsize>(records.size()));
    // Hand each finished block to the OS, so a recorder that crashes loses at most the open
    // block (the reader recovers every complete block before the missing end marker).
    out.flush();
    records.clear();
    block_count = 0;
    checkStream();
  }

  void appendBinary(const Event& e) {
    // |t - base| through unsigned arithmetic: exact for any two int64 values, no overflow.
    const auto t = static_cast<std::uint64_t>(e.t_us);
    const auto base = static_cast<std::uint64_t>(block_base);
    const bool fits = block_count > 0 &&
                      (e.t_us >= block_base ? t - base <= 0x7FFFFFFFu : base - t <= 0x80000000u);
    if (!fits || block_count == kWriterBlockEvents) {
      flushBlock();
      block_base = e.t_us;
    }
    std::uint8_t r[kRecordBytes];
    putU32(r, static_cast<std::uint32_t>(static_cast<std::int32_t>(e.t_us - block_base)));
    putU16(r + 4, e.x);
    putU16(r + 6, static_cast<std::uint16_t>(e.y | (e.polarity ? kPolarityBit : 0)));
    records.insert(records.end(), r, r + kRecordBytes);
    ++block_count;
  }

  template <typename Integer>
  void appendInteger(Integer value) {
    char digits[24];
    const auto result = std::to_chars(digits, digits + sizeof(digits), value);
    text.append(digits, result.ptr);
  }

  void appendText(const Event& e) {
    if (format == EventFileFormat::kRpgText) {
      // Seconds with exactly 6 decimals, formatted from integers (no rounding).
      const std::uint64_t magnitude =
          e.t_us < 0 ? 0 - static_cast<std::uint64_t>(e.t_us) : static_cast<std::uint64_t>(e.t_us);
      if (e.t_us < 0) text.push_back('-');
      appendInteger(magnitude / 1000000);
      char fraction[7] = {'.', '0', '0', '0', '0', '0', '0'};
      std::uint64_t micros = magnitude % 1000000;
      for (int i = 6; i >= 1; --i) {
        fraction[i] = static_cast<char>('0' + micros % 10);
        micros /= 10;
      }
      text.append(fraction, sizeof(fraction));
    } else {
      appendInteger(e.t_us);
    }
    text.push_back(' ');
    appendInteger(e.x);
    text.push_back(' ');
    appendInteger(e.y);
    text.push_back(' ');
    text.push_back(e.polarity ? '1' : '0');
    text.push_back('\n');
  }
};

EventFileWriter::EventFileWriter(const std::string& path, const SensorSize& sensor,
                                 EventFileFormat format)
    : impl_(std::make_unique<Impl>()) {
  if (format == EventFileFormat::kBinary) checkBinarySensor(sensor);
  if (sensor.width == 0 || sensor.height == 0 || sensor.width > 65536 || sensor.height > 65536) {
    throw std::invalid_argument("event file: sensor size " + sensorText(sensor) + " invalid");
  }
  impl_->path = path;
  impl_->format = format;
  impl_->sensor = sensor;
  impl_->out.open(path, std::ios::binary | std::ios::trunc);
  if (!impl_->out) throw std::runtime_error("cannot create event file '" + path + "'");
  impl_->writeHeader();
}

EventFileWriter EventFileWriter::openForAppend(const std::string& path,
                                               std::optional<SensorSize> sensor) {
  EventReadOptions options;
  options.sensor = sensor;
  EventFileReader reader(path, options);
  EventVector batch;
  while (reader.next(batch, 1 << 16) > 0) {
  }
  if (reader.error()) {
    throw std::runtime_error("cannot append to damaged event file '" + path +
                             "': " + *reader.error());
  }
  const EventFileFormat format = reader.format();
  const SensorSize file_sensor = reader.sensor();
  if (format == EventFileFormat::kBinary && sensor &&
      (sensor->width != file_sensor.width || sensor->height != file_sensor.height)) {
    throw std::invalid_argument("openForAppend: sensor " + sensorText(*sensor) +
                                " differs from the file's " + sensorText(file_sensor));
  }
  if (format == EventFileFormat::kText && !sensor) {
    // Without a header the size was inferred from the events; later ones could lie outside.
    std::ifstream in(path, std::ios::binary);
    if (readPrefix(in, kDetectBytes).rfind(kTextHeaderPrefix, 0) != 0) {
      throw std::invalid_argument("openForAppend: '" + path +
                                  "' declares no sensor size; pass one");
    }
  }
  EventFileWriter writer;
  writer.impl_ = std::make_unique<Impl>();
  Impl& impl = *writer.impl_;
  impl.path = path;
  impl.format = format;
  impl.sensor = file_sensor;
  impl.written = reader.eventsRead();
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw std::runtime_error("cannot stat event file '" + path + "': " + ec.message());
  bool needs_newline = false;
  if (format == EventFileFormat::kBinary) {
    // A clean binary file ends with its 24-byte end marker; close() writes a new one.
    std::filesystem::resize_file(path, size - kBlockHeaderBytes, ec);
    if (ec) throw std::runtime_error("cannot truncate event file '" + path + "': " + ec.message());
  } else if (size > 0) {
    std::ifstream in(path, std::ios::binary);
    in.seekg(static_cast<std::streamoff>(size - 1));
    needs_newline = in.get() != '\n';
  }
  impl.out.open(path, std::ios::binary | std::ios::app);
  if (!impl.out) throw std::runtime_error("cannot open event file '" + path + "' for appending");
  if (needs_newline) impl.out.put('\n');
  impl.checkStream();
  return writer;
}

EventFileWriter::~EventFileWriter() {
  if (!impl_ || impl_->closed) return;
  try {
    close();
  } catch (const std::exception&) {
    // Destructors must not throw; call close() to see I/O errors.
  }
}

EventFileWriter::EventFileWriter(EventFileWriter&&) noexcept = default;
EventFileWriter& EventFileWriter::operator=(EventFileWriter&& other) noexcept {
  if (this != &other) {
    if (impl_ && !impl_->closed) {
      try {
        close();
      } catch (const std::exception&) {
        // as in the destructor
      }
    }
    impl_ = std::move(other.impl_);
  }
  return *this;
}

void EventFileWriter::write(const EventVector& events) {
  if (!impl_ || impl_->closed) throw std::logic_error("EventFileWriter: write after close");
  for (std::size_t i = 0; i < events.size(); ++i) {
    if (!impl_->sensor.contains(events[i])) {
      throw std::invalid_argument("EventFileWriter: event " + std::to_string(i) + " at (" +
                                  std::to_string(events[i].x) + ", " + std::to_string(events[i].y) +
                                  ") outside the " + sensorText(impl_->sensor) + " sensor");
    }
  }
  if (impl_->format == EventFileFormat::kBinary) {
    for (const Event& e : events) impl_->appendBinary(e);
    // Keep at most one open block in memory.
    if (impl_->block_count == kWriterBlockEvents) impl_->flushBlock();
  } else {
    for (const Event& e : events) {
      impl_->appendText(e);
      if (impl_->text.size() > (1u << 20)) {
        impl_->out.write(impl_->text.data(), static_cast<std::streamsize>(impl_->text.size()));
        impl_->text.clear();
        impl_->checkStream();
      }
    }
  }
  impl_->written += events.size();
}

void EventFileWriter::write(const Event& event) { write(EventVector{event}); }

void EventFileWriter::close() {
  if (!impl_ || impl_->closed) throw std::logic_error("EventFileWriter: close after close");
  impl_->closed = true;
  if (impl_->format == EventFileFormat::kBinary) {
    impl_->flushBlock();
    impl_->writeEndMarker();
  } else {
    impl_->out.write(impl_->text.data(), static_cast<std::streamsize>(impl_->text.size()));
    impl_->text.clear();
  }
  impl_->out.flush();
  impl_->checkStream();
  impl_->out.close();
  if (impl_->out.fail()) throw std::runtime_error("error closing event file '" + impl_->path + "'");
}

std::size_t EventFileWriter::eventsWritten() const { return impl_ ? impl_->written : 0; }

void writeEventFile(const std::string& path, const EventVector& events, const SensorSize& sensor,
                    EventFileFormat format) {
  for (std::size_t i = 0; i < events.size(); ++i) {
    if (!sensor.contains(events[i])) {
      throw std::invalid_argument("writeEventFile: event " + std::to_string(i) + " at (" +
                                  std::to_string(events[i].x) + ", " + std::to_string(events[i].y) +
                                  ") outside the " + sensorText(sensor) + " sensor");
    }
  }
  EventFileWriter writer(path, sensor, format);
  writer.write(events);
  writer.close();
}

}  // namespace ebslam

#include "ebslam/events/event_io.h"

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

#include "event_file_codec.h"

namespace ebslam {

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

}  // namespace ebslam

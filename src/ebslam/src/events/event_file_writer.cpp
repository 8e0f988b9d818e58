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

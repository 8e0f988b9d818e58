#pragma once

// Event files: the project's binary format (kBinary: versioned, CRC-checked blocks), plain text
// (kText: `t x y p`, t in integer us or decimal s) and the Event Camera Dataset's `events.txt`
// (kRpgText). Readers never throw for a damaged file once it is open: they stop at the first
// damage, keep every valid event before it and describe it in EventReadResult::error; events come
// in file order, backward time steps are counted, not reordered. Byte layouts, damage rules and
// the sensor-size rules: docs/event_file_format.md.

#include <cstddef>
#include <cstdint>
#include <istream>
#include <memory>
#include <optional>
#include <string>

#include "ebslam/events/event.h"

namespace ebslam {

enum class EventFileFormat { kBinary, kText, kRpgText };

/// Short lower-case name ("binary", "text", "rpg") for messages and command lines.
const char* toString(EventFileFormat format);
/// Parses "binary"/"bin"/"ebe", "text"/"txt", "rpg"/"rpg-text"/"ecd"; std::nullopt otherwise.
std::optional<EventFileFormat> parseEventFileFormat(const std::string& name);

/// Everything read from one event file.
struct EventReadResult {
  EventVector events;  ///< every complete, valid event before any damage, in file order
  SensorSize sensor;   ///< from the file header, the caller, or the format's default
  std::optional<std::string> error;  ///< set on truncation/corruption: what and where
  std::size_t non_monotonic = 0;     ///< number of events whose t_us < the previous event's
  std::optional<std::size_t> first_non_monotonic_index;  ///< index into events of the first one
};

/// Options for reading; all optional.
struct EventReadOptions {
  std::optional<EventFileFormat> format;  ///< detected from magic/content when unset
  /// Sensor size of the text formats; takes precedence over a kText header comment and the
  /// kRpgText default. For kText without header and without this, the size is the bounding box
  /// of the events. Ignored for kBinary, whose header is authoritative.
  std::optional<SensorSize> sensor;
};

/// Detects the format of an existing file: a file starting with (a prefix of) the binary magic
/// => kBinary; the kText header comment => kText; else the first data line decides: a
/// timestamp with a decimal point => kRpgText, an integer timestamp (or no data) => kText.
/// Throws std::runtime_error if the file cannot be opened.
EventFileFormat detectEventFileFormat(const std::string& path);

/// Default format for writing a path: ".txt" => kText, anything else => kBinary.
EventFileFormat eventFileFormatFromExtension(const std::string& path);

/// Reads a whole event file. Throws std::runtime_error if it cannot be opened; damage inside the
/// file is reported in the result's error instead (see the header comment).
EventReadResult readEventFile(const std::string& path,
                              std::optional<EventFileFormat> format = std::nullopt);
EventReadResult readEventFile(const std::string& path, const EventReadOptions& options);

/// Writes a whole event file. Throws std::runtime_error on I/O failure and
/// std::invalid_argument for events outside `sensor` or a sensor the format cannot hold
/// (binary: width <= 65535, height <= 32768).
void writeEventFile(const std::string& path, const EventVector& events, const SensorSize& sensor,
                    EventFileFormat format = EventFileFormat::kBinary);

/// Stable sort by timestamp (events with equal time keep their file order).
void sortEventsByTime(EventVector& events);

/// Streaming reader for large files: reads batches without loading the whole file.
///
///   EventFileReader reader(path);
///   EventVector batch;
///   while (reader.next(batch, 100000) > 0) { ...; }
///   if (reader.error()) { ... }
class EventFileReader {
 public:
  /// Opens the file and reads its header. Throws std::runtime_error if it cannot be opened.
  /// A damaged header does not throw: the reader starts in the done() state with error() set.
  explicit EventFileReader(const std::string& path, const EventReadOptions& options = {});
  /// Reads from an already open stream (opened in binary mode), e.g. memory for tests and
  /// fuzzing. Without options.format the format is detected from the content only.
  explicit EventFileReader(std::unique_ptr<std::istream> stream,
                           const EventReadOptions& options = {});
  ~EventFileReader();
  EventFileReader(EventFileReader&&) noexcept;
  EventFileReader& operator=(EventFileReader&&) noexcept;
  EventFileReader(const EventFileReader&) = delete;
  EventFileReader& operator=(const EventFileReader&) = delete;

  /// Replaces `batch` with the next up to `max_events` events; returns how many (0 when done).
  std::size_t next(EventVector& batch, std::size_t max_events);

  EventFileFormat format() const;
  /// Sensor size. For kText without header and without EventReadOptions::sensor this is the
  /// bounding box of the events read so far (final once done()).
  SensorSize sensor() const;
  bool done() const;  ///< end of file or damage reached
  const std::optional<std::string>& error() const;
  std::size_t eventsRead() const;         ///< total events returned so far
  std::size_t nonMonotonicCount() const;  ///< events so far whose t_us < previous t_us
  std::optional<std::size_t> firstNonMonotonicIndex() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Streaming writer: append events in as many calls as needed, then close() (the destructor
/// closes too but swallows errors, so call close() to learn about I/O failures).
class EventFileWriter {
 public:
  /// Creates/truncates the file and writes the header. Throws std::runtime_error if it cannot
  /// be created and std::invalid_argument for a sensor the format cannot hold.
  EventFileWriter(const std::string& path, const SensorSize& sensor,
                  EventFileFormat format = EventFileFormat::kBinary);
  /// Opens an existing, undamaged event file to append to it (e.g. a recorder that restarts).
  /// The format and sensor size come from the file; `sensor` is required for a kText file
  /// without header and must match otherwise. The file is read once to validate and count it;
  /// new events go after the existing ones (binary: the end marker is replaced on close()).
  /// Throws std::runtime_error if the file cannot be opened or is damaged (the reader's message)
  /// and std::invalid_argument for a sensor mismatch.
  static EventFileWriter openForAppend(const std::string& path,
                                       std::optional<SensorSize> sensor = std::nullopt);
  ~EventFileWriter();
  EventFileWriter(EventFileWriter&&) noexcept;
  EventFileWriter& operator=(EventFileWriter&&) noexcept;
  EventFileWriter(const EventFileWriter&) = delete;
  EventFileWriter& operator=(const EventFileWriter&) = delete;

  /// Appends events. Throws std::invalid_argument for an event outside the sensor (nothing of
  /// that call is written then) and std::runtime_error on I/O failure.
  void write(const EventVector& events);
  void write(const Event& event);
  /// Flushes buffered events (binary: ends the current block) and closes the file.
  /// Throws std::runtime_error on I/O failure. Further writes throw std::logic_error.
  void close();
  std::size_t eventsWritten() const;

 private:
  EventFileWriter() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ebslam

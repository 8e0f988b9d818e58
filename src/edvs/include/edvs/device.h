#pragma once

// An eDVS reached through a URI: opening, reset, configuration, streaming, biases. ROS-free.
// URIs: serial:///dev/ttyUSB0?baud=4000000&format=E2, serial://?serial_number=FT4XYZ12,
// tcp://192.168.201.62:56000?format=E3, file:///path/capture.raw?format=E2&rate=400000&loop=1.
// Every query key and its values: edvs_driver/README.md, "Device URIs".

#include <array>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ebslam/events/event.h"
#include "edvs/biases.h"
#include "edvs/commands.h"
#include "edvs/event_format.h"
#include "edvs/event_parser.h"
#include "edvs/transport.h"

namespace edvs {

struct DeviceUri {
  enum class Scheme { kSerial, kTcp, kFile };
  Scheme scheme = Scheme::kSerial;
  std::string path;                          ///< serial device node or capture file
  std::optional<std::string> serial_number;  ///< serial: choose the FTDI bridge by serial
  std::string host;                          ///< tcp
  int port = 0;                              ///< tcp
  int baud = 4000000;                        ///< serial line rate [bit/s]
  bool rtscts = true;                        ///< serial hardware flow control
  std::optional<EventFormat> format;         ///< from `format=`, if given
  Firmware firmware = Firmware::kCurrent;
  double file_rate = 400000.0;  ///< file pacing [bytes/s], 0 = unpaced
  bool file_loop = false;       ///< file: replay again from the start at its end (loop=1)
};

/// Parses a device URI. Throws std::invalid_argument naming the problem (unknown scheme,
/// missing path/host/port, unknown query key, bad value).
DeviceUri parseDeviceUri(const std::string& uri);

/// Settings of one device session.
struct DeviceConfig {
  std::string uri = "serial:///dev/ttyUSB0";
  /// Event format when the URI does not give one. 16-bit timestamps are what most eDVS
  /// recordings use; 24/32 bit survive longer quiet gaps.
  EventFormat format = EventFormat::kAbs16;
  Firmware firmware = Firmware::kCurrent;  ///< overridden by the URI's firmware= if given
  SyncMode sync = SyncMode::kNone;
  int on_bit = 1;                          ///< polarity bit meaning ON (see event_format.h)
  int banner_timeout_ms = 1500;            ///< wait for the reset banner [ms]
  int command_gap_ms = 10;                 ///< pause after each command [ms]
  bool require_banner = true;              ///< fail the open if no banner arrives (no device there)
  bool infer_wraps_from_host_time = true;  ///< see ParserConfig
};

/// Counters of one device, cumulative over reconnects of the same EdvsDevice.
struct DeviceStats {
  ParserStats parser;
  std::uint64_t bytes_read = 0;
};

/// One eDVS session. Not thread-safe: call from one thread (the driver's reading thread);
/// setBias() may be called from another thread only through the owner's synchronisation.
class EdvsDevice {
 public:
  using TransportFactory = std::function<std::unique_ptr<Transport>(const DeviceUri&)>;

  /// Throws std::invalid_argument for a bad URI or config. The factory opens the transport;
  /// the default one opens serial/TCP/file as the URI says (tests inject their own).
  explicit EdvsDevice(DeviceConfig config, TransportFactory factory = {});
  ~EdvsDevice();

  /// Opens the transport, stops a stream left running, resets the device and waits for its
  /// banner, turns echo off, discards stale bytes, selects the event format and the sync mode.
  /// Throws std::runtime_error with a message naming what is missing when there is no device.
  void open();
  /// Starts streaming (E+, master: !ETM+), then sends the biases set so far: bias commands are
  /// only ever sent while streaming, because a camera that receives them otherwise freezes.
  void start();
  /// Stops streaming (E-). Keeps the transport open.
  void stop();
  /// Closes the transport (no commands sent).
  void close();
  bool isOpen() const { return transport_ != nullptr; }
  bool streaming() const { return streaming_; }

  /// Reads what arrived within `timeout_ms` and appends the decoded events (device time,
  /// unwrapped, microseconds). host_us is stamped from CLOCK_MONOTONIC. Returns the number of
  /// events appended. With a timestamped format the last few events of a read wait for the
  /// next one to confirm them (see EventParser); a read that times out without bytes releases
  /// them. Throws DeviceGone when the device disappears (after a last read that returns the
  /// events still held, if any).
  std::size_t read(ebslam::EventVector& out, int timeout_ms);

  /// Sets one bias (index 0..11, 24-bit value). Sent at once while streaming (followed by !BF),
  /// otherwise remembered and sent right after the next start().
  void setBias(int index, std::int64_t value);
  const std::array<std::optional<std::int64_t>, kNumBiases>& biases() const { return biases_; }

  const DeviceUri& uri() const { return uri_; }
  EventFormat format() const { return format_; }
  const DeviceStats& stats() const;
  /// The stream does not look like the configured format (see EventParser::formatSuspect).
  bool formatSuspect() const { return parser_.formatSuspect(); }
  /// The banner text the device printed on reset (empty for a capture file).
  const std::string& banner() const { return banner_; }
  std::string describe() const;

 private:
  void send(const std::string& command);
  void sendBiases();

  DeviceConfig config_;
  DeviceUri uri_;
  EventFormat format_;
  TransportFactory factory_;
  std::unique_ptr<Transport> transport_;
  EventParser parser_;
  mutable DeviceStats stats_;
  std::array<std::optional<std::int64_t>, kNumBiases> biases_{};
  bool biases_dirty_ = false;
  bool streaming_ = false;
  std::string banner_;
  std::vector<std::uint8_t> buffer_;
  std::exception_ptr gone_;  // a DeviceGone held back while the last events were handed out
};

/// Opens the transport a URI names (resolving serial_number through USB discovery).
std::unique_ptr<Transport> openTransport(const DeviceUri& uri);

/// Monotonic host time [us] (CLOCK_MONOTONIC), the clock passed to the parser.
std::int64_t monotonicMicros();

}  // namespace edvs

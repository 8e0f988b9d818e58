#pragma once

// Byte transports to an eDVS: serial port (termios, custom baud rates, RTS/CTS), TCP (the eDVS
// WiFi module speaks the same protocol) and a raw capture file. ROS-free.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>

namespace edvs {

/// The device went away while open (unplugged, emulator closed, connection reset).
class DeviceGone : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A capture file was read to its end (a DeviceGone: the stream is over, not lost).
class CaptureEnded : public DeviceGone {
 public:
  using DeviceGone::DeviceGone;
};

/// A bidirectional byte stream to an eDVS.
class Transport {
 public:
  virtual ~Transport() = default;
  /// Reads up to `size` bytes, waiting at most `timeout_ms` for the first one. Returns the
  /// number read, 0 on timeout. Throws DeviceGone when the device is gone (a capture file
  /// throws CaptureEnded at its end).
  virtual std::size_t read(std::uint8_t* buffer, std::size_t size, int timeout_ms) = 0;
  /// Writes all of `data` in one write call (one command per call: several commands in one
  /// write confuse the firmware). Throws DeviceGone on failure.
  virtual void write(std::string_view data) = 0;
  /// Discards bytes received but not yet read (stale data from a previous session).
  virtual void discardInput() = 0;
  /// True if commands reach a real device (false for a capture file: nothing to configure).
  virtual bool acceptsCommands() const { return true; }
  /// Human-readable description for messages ("serial /dev/ttyUSB0 @ 4000000 baud").
  virtual std::string describe() const = 0;
};

struct SerialOptions {
  std::string path;    ///< e.g. /dev/ttyUSB0 or a udev symlink /dev/edvs
  int baud = 4000000;  ///< line rate [bit/s]; 4 Mbit/s is the eDVS standard
  bool rtscts = true;  ///< RTS/CTS hardware flow control (the eDVS uses it)
};

/// Opens and configures a serial port: raw 8N1, RTS/CTS as requested, the baud rate through the
/// standard constants where one exists and the Linux BOTHER interface otherwise. Throws
/// std::runtime_error naming what is missing: no such device node, no permission (dialout group
/// or udev rule), not a serial port, or a baud rate the driver refuses.
std::unique_ptr<Transport> openSerial(const SerialOptions& options);

/// Connects to host:port (the eDVS WiFi module). Throws std::runtime_error with the reason
/// (unknown host, connection refused, timeout).
std::unique_ptr<Transport> openTcp(const std::string& host, int port, int timeout_ms = 2000);

/// Replays a raw capture of the byte stream, paced at `bytes_per_second` (0 = as fast as read).
/// Writes are ignored. Throws std::runtime_error if the file cannot be opened.
std::unique_ptr<Transport> openCaptureFile(const std::string& path, double bytes_per_second);

/// Baud rate the port actually runs at (for tests); throws std::runtime_error on failure.
int serialBaudRate(int fd);
/// Sets a baud rate, standard or not (Linux BOTHER); returns false if the driver refuses.
bool setSerialBaudRate(int fd, int baud);

}  // namespace edvs

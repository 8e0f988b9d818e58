#include "edvs/device.h"

#include <time.h>

#include <chrono>
#include <cstdlib>
#include <stdexcept>
#include <thread>

#include "edvs/usb_discovery.h"

namespace edvs {

namespace {

int parseInt(const std::string& key, const std::string& value, long lo, long hi) {
  char* end = nullptr;
  const long v = std::strtol(value.c_str(), &end, 10);
  if (value.empty() || *end != '\0' || v < lo || v > hi) {
    throw std::invalid_argument("device URI: " + key + "=" + value + " is not an integer in " +
                                std::to_string(lo) + ".." + std::to_string(hi));
  }
  return static_cast<int>(v);
}

}  // namespace

std::int64_t monotonicMicros() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}

DeviceUri parseDeviceUri(const std::string& uri) {
  DeviceUri out;
  const auto sep = uri.find("://");
  if (sep == std::string::npos) {
    throw std::invalid_argument("device URI '" + uri +
                                "' has no scheme; use serial:///dev/ttyUSB0, tcp://host:port "
                                "or file:///path");
  }
  const std::string scheme = uri.substr(0, sep);
  std::string rest = uri.substr(sep + 3);
  std::string query;
  if (const auto q = rest.find('?'); q != std::string::npos) {
    query = rest.substr(q + 1);
    rest.resize(q);
  }
  std::optional<std::string> format_text;
  // Query first: firmware= changes how format= is read.
  std::size_t pos = 0;
  while (pos < query.size()) {
    std::size_t amp = query.find('&', pos);
    if (amp == std::string::npos) amp = query.size();
    const std::string item = query.substr(pos, amp - pos);
    pos = amp + 1;
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos) {
      throw std::invalid_argument("device URI: query item '" + item + "' has no '='");
    }
    const std::string key = item.substr(0, eq);
    const std::string value = item.substr(eq + 1);
    if (key == "baud" || key == "baudrate") {
      out.baud = parseInt(key, value, 1200, 50000000);
    } else if (key == "rtscts") {
      out.rtscts = parseInt(key, value, 0, 1) == 1;
    } else if (key == "format") {
      format_text = value;
    } else if (key == "firmware") {
      const auto fw = parseFirmware(value);
      if (!fw) throw std::invalid_argument("device URI: firmware must be current or legacy");
      out.firmware = *fw;
    } else if (key == "serial_number" || key == "serial") {
      out.serial_number = value;
    } else if (key == "loop") {
      out.file_loop = parseInt(key, value, 0, 1) == 1;
    } else if (key == "rate") {
      char* end = nullptr;
      out.file_rate = std::strtod(value.c_str(), &end);
      if (value.empty() || *end != '\0' || out.file_rate < 0) {
        throw std::invalid_argument("device URI: rate must be a number of bytes/s >= 0");
      }
    } else {
      throw std::invalid_argument(
          "device URI: unknown query key '" + key +
          "' (known: baud, rtscts, format, firmware, serial_number, rate, loop)");
    }
  }
  if (format_text) {
    out.format = parseEventFormat(*format_text, out.firmware);
    if (!out.format) {
      throw std::invalid_argument("device URI: format '" + *format_text + "' is not one of E0..E" +
                                  std::string(out.firmware == Firmware::kLegacy ? "3" : "4") +
                                  " (" + toString(out.firmware) +
                                  " firmware) or none/delta/ts16/ts24/ts32");
    }
    if (*out.format == EventFormat::kDelta && out.firmware == Firmware::kLegacy) {
      throw std::invalid_argument("device URI: legacy firmware has no delta format");
    }
  }
  if (scheme == "serial") {
    out.scheme = DeviceUri::Scheme::kSerial;
    out.path = rest;
    if (out.path.empty() && !out.serial_number) {
      throw std::invalid_argument("device URI '" + uri +
                                  "' names no serial port: serial:///dev/ttyUSB0 or "
                                  "serial://?serial_number=<FTDI serial>");
    }
  } else if (scheme == "tcp") {
    out.scheme = DeviceUri::Scheme::kTcp;
    const auto colon = rest.rfind(':');
    if (colon == std::string::npos || colon == 0) {
      throw std::invalid_argument("device URI '" + uri + "' needs host and port: tcp://host:port");
    }
    out.host = rest.substr(0, colon);
    if (out.host.size() > 2 && out.host.front() == '[' && out.host.back() == ']') {
      out.host = out.host.substr(1, out.host.size() - 2);
    }
    out.port = parseInt("port", rest.substr(colon + 1), 1, 65535);
  } else if (scheme == "file") {
    out.scheme = DeviceUri::Scheme::kFile;
    out.path = rest;
    if (out.path.empty()) throw std::invalid_argument("device URI '" + uri + "' names no file");
  } else {
    throw std::invalid_argument("device URI scheme '" + scheme +
                                "' unknown; use serial, tcp or file");
  }
  return out;
}

std::unique_ptr<Transport> openTransport(const DeviceUri& uri) {
  switch (uri.scheme) {
    case DeviceUri::Scheme::kSerial: {
      SerialOptions options;
      options.path = uri.path;
      if (uri.serial_number) options.path = findTtyBySerialNumber(*uri.serial_number);
      options.baud = uri.baud;
      options.rtscts = uri.rtscts;
      return openSerial(options);
    }
    case DeviceUri::Scheme::kTcp:
      return openTcp(uri.host, uri.port);
    case DeviceUri::Scheme::kFile:
      return openCaptureFile(uri.path, uri.file_rate);
  }
  throw std::logic_error("unhandled URI scheme");
}

EdvsDevice::EdvsDevice(DeviceConfig config, TransportFactory factory)
    : config_(std::move(config)),
      uri_(parseDeviceUri(config_.uri)),
      format_(uri_.format.value_or(config_.format)),
      factory_(factory ? std::move(factory) : TransportFactory(openTransport)) {
  if (config_.uri.find("firmware=") == std::string::npos) uri_.firmware = config_.firmware;
  if (format_ == EventFormat::kDelta && uri_.firmware == Firmware::kLegacy) {
    throw std::invalid_argument("legacy eDVS firmware has no delta-timestamp format");
  }
  if (config_.banner_timeout_ms < 0 || config_.command_gap_ms < 0) {
    throw std::invalid_argument("DeviceConfig timeouts must be >= 0");
  }
  ParserConfig pc;
  pc.format = format_;
  pc.on_bit = config_.on_bit;
  pc.infer_wraps_from_host_time = config_.infer_wraps_from_host_time;
  // What the line carries tells a backlog from a live stream: a serial line at 8N1, a paced
  // capture at its rate; TCP has no fixed rate.
  switch (uri_.scheme) {
    case DeviceUri::Scheme::kSerial:
      pc.line_bytes_per_s = uri_.baud / 10.0;
      break;
    case DeviceUri::Scheme::kFile:
      pc.line_bytes_per_s = uri_.file_rate;
      break;
    case DeviceUri::Scheme::kTcp:
      break;
  }
  parser_ = EventParser(pc);
  buffer_.resize(1 << 16);
}

EdvsDevice::~EdvsDevice() {
  try {
    if (transport_ && streaming_) stop();
  } catch (const std::exception&) {
    // The device is gone already; nothing to stop.
  }
}

std::string EdvsDevice::describe() const {
  return transport_ ? transport_->describe() : config_.uri;
}

void EdvsDevice::send(const std::string& command) {
  transport_->write(command);  // exactly one command per write
  if (config_.command_gap_ms > 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(config_.command_gap_ms));
  }
}

void EdvsDevice::open() {
  close();
  transport_ = factory_(uri_);
  gone_ = nullptr;
  streaming_ = false;
  banner_.clear();
  parser_.restart();
  if (!transport_->acceptsCommands()) return;
  // A stream left running by a previous session keeps sending: stop it, then drop what came.
  send(commands::stopStreaming());
  transport_->discardInput();
  send(commands::reset());
  // The banner may be preceded by event bytes still in flight; search the accumulated text.
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(config_.banner_timeout_ms);
  std::string received;
  while (std::chrono::steady_clock::now() < deadline) {
    const std::size_t n = transport_->read(buffer_.data(), buffer_.size(), 20);
    received.append(reinterpret_cast<const char*>(buffer_.data()), n);
    if (containsBanner(received)) break;
  }
  if (containsBanner(received)) {
    const auto at = received.find("EDVS-4337") != std::string::npos ? received.find("EDVS-4337")
                                                                    : received.find("meDVS128");
    const auto eol = received.find_first_of("\r\n", at);
    banner_ = received.substr(at, eol == std::string::npos ? std::string::npos : eol - at);
  } else if (config_.require_banner) {
    const std::string what = transport_->describe();
    transport_.reset();
    throw std::runtime_error(
        "no eDVS answered on " + what + ": no reset banner (EDVS-4337 or meDVS128) within " +
        std::to_string(config_.banner_timeout_ms) + " ms" +
        (received.empty() ? std::string(" and no bytes at all")
                          : " (received " + std::to_string(received.size()) + " other bytes)") +
        "; check power, cable, baud rate (" + std::to_string(uri_.baud) + ") and flow control");
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(config_.command_gap_ms));
  send(commands::echoOff());
  transport_->discardInput();  // the rest of the banner and the echo of !U0
  send(commands::eventFormat(format_, uri_.firmware));
  switch (config_.sync) {
    case SyncMode::kMaster:
      send(commands::masterStop());  // armed, clock held until start()
      break;
    case SyncMode::kSlave:
      send(commands::slave());
      break;
    case SyncMode::kNone:
      send(commands::timestampReset());
      break;
  }
  transport_->discardInput();
  parser_.restart();
}

void EdvsDevice::start() {
  if (!transport_) throw std::logic_error("EdvsDevice::start() before open()");
  if (streaming_) return;
  if (transport_->acceptsCommands()) {
    if (config_.sync == SyncMode::kMaster) send(commands::masterRun());
    send(commands::startStreaming());
  }
  streaming_ = true;
  biases_dirty_ = true;
  sendBiases();
}

void EdvsDevice::stop() {
  if (!transport_ || !streaming_) return;
  streaming_ = false;
  if (transport_->acceptsCommands()) send(commands::stopStreaming());
}

void EdvsDevice::close() {
  transport_.reset();
  streaming_ = false;
}

void EdvsDevice::setBias(int index, std::int64_t value) {
  const std::string command = commands::setBias(index, value);  // validates
  biases_[static_cast<std::size_t>(index)] = value;
  if (streaming_ && transport_ && transport_->acceptsCommands()) {
    send(command);
    send(commands::flushBiases());
  } else {
    biases_dirty_ = true;
  }
}

void EdvsDevice::sendBiases() {
  if (!streaming_ || !biases_dirty_ || !transport_ || !transport_->acceptsCommands()) return;
  bool any = false;
  for (int i = 0; i < kNumBiases; ++i) {
    if (const auto& v = biases_[static_cast<std::size_t>(i)]) {
      send(commands::setBias(i, *v));
      any = true;
    }
  }
  if (any) send(commands::flushBiases());
  biases_dirty_ = false;
}

std::size_t EdvsDevice::read(ebslam::EventVector& out, int timeout_ms) {
  if (!transport_) throw DeviceGone("eDVS not open");
  if (gone_) {
    std::exception_ptr gone = gone_;
    gone_ = nullptr;
    std::rethrow_exception(gone);
  }
  std::size_t n = 0;
  try {
    n = transport_->read(buffer_.data(), buffer_.size(), timeout_ms);
  } catch (const DeviceGone&) {
    // The events still waiting for confirmation are complete: hand them out first and report
    // the loss at the next read.
    const std::size_t flushed = parser_.flush(out);
    if (flushed == 0) throw;
    gone_ = std::current_exception();
    return flushed;
  }
  if (n == 0) {
    // The line is idle: no further bytes will confirm the events held back; decide them now.
    parser_.noteIdle(monotonicMicros());
    return parser_.flush(out);
  }
  stats_.bytes_read += n;
  // A capture replays bytes whose arrival times were not recorded: no host time for them.
  const std::optional<std::int64_t> host_us =
      transport_->acceptsCommands() ? std::optional<std::int64_t>(monotonicMicros()) : std::nullopt;
  return parser_.feed(buffer_.data(), n, host_us, out);
}

const DeviceStats& EdvsDevice::stats() const {
  stats_.parser = parser_.stats();
  return stats_;
}

}  // namespace edvs

#include "edvs/transport.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <thread>
#include <vector>

namespace edvs {

namespace {

std::string errnoText(int err) { return std::strerror(err); }

/// Owns a file descriptor.
class Fd {
 public:
  explicit Fd(int fd = -1) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }

 private:
  int fd_;
};

/// Reads with poll() so that a timeout never blocks longer than asked.
std::size_t pollRead(int fd, std::uint8_t* buffer, std::size_t size, int timeout_ms,
                     const std::string& what) {
  pollfd p{fd, POLLIN, 0};
  const int r = ::poll(&p, 1, timeout_ms);
  if (r < 0) {
    if (errno == EINTR) return 0;
    throw DeviceGone(what + ": poll failed: " + errnoText(errno));
  }
  if (r == 0) return 0;
  if (p.revents & (POLLERR | POLLNVAL)) throw DeviceGone(what + ": device error or closed");
  const ssize_t n = ::read(fd, buffer, size);
  if (n > 0) return static_cast<std::size_t>(n);
  if (n == 0) throw DeviceGone(what + ": device closed the connection");
  if (errno == EAGAIN || errno == EINTR) return 0;
  // EIO: the other end of a pty or a USB serial adapter went away.
  throw DeviceGone(what + ": read failed: " + errnoText(errno));
}

void writeAll(int fd, std::string_view data, const std::string& what) {
  // One write() call carries the whole command; a short write is finished with another
  // (the device still sees one command, just in two pieces on the line).
  std::size_t done = 0;
  int spins = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EINTR) && ++spins < 1000) {
      pollfd p{fd, POLLOUT, 0};
      ::poll(&p, 1, 10);
      continue;
    }
    throw DeviceGone(what + ": write failed: " + errnoText(errno));
  }
}

class SerialTransport : public Transport {
 public:
  SerialTransport(int fd, SerialOptions options) : fd_(fd), options_(std::move(options)) {}
  std::size_t read(std::uint8_t* buffer, std::size_t size, int timeout_ms) override {
    return pollRead(fd_.get(), buffer, size, timeout_ms, describe());
  }
  void write(std::string_view data) override {
    writeAll(fd_.get(), data, describe());
    ::tcdrain(fd_.get());  // on the line before the next command
  }
  void discardInput() override {
    ::tcflush(fd_.get(), TCIFLUSH);
    // Bytes still in flight in the adapter arrive after the flush: drain until quiet.
    std::uint8_t sink[4096];
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
    while (std::chrono::steady_clock::now() < deadline && read(sink, sizeof(sink), 20) > 0) {
    }
  }
  std::string describe() const override {
    return "serial " + options_.path + " @ " + std::to_string(options_.baud) + " baud";
  }

 private:
  Fd fd_;
  SerialOptions options_;
};

class TcpTransport : public Transport {
 public:
  TcpTransport(int fd, std::string name) : fd_(fd), name_(std::move(name)) {}
  std::size_t read(std::uint8_t* buffer, std::size_t size, int timeout_ms) override {
    return pollRead(fd_.get(), buffer, size, timeout_ms, describe());
  }
  void write(std::string_view data) override { writeAll(fd_.get(), data, describe()); }
  void discardInput() override {
    std::uint8_t sink[4096];
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
    while (std::chrono::steady_clock::now() < deadline && read(sink, sizeof(sink), 20) > 0) {
    }
  }
  std::string describe() const override { return "tcp " + name_; }

 private:
  Fd fd_;
  std::string name_;
};

class CaptureFileTransport : public Transport {
 public:
  CaptureFileTransport(std::string path, double bytes_per_second)
      : path_(std::move(path)), in_(path_, std::ios::binary), rate_(bytes_per_second) {
    if (!in_) throw std::runtime_error("cannot open capture file " + path_);
    start_ = std::chrono::steady_clock::now();
  }
  std::size_t read(std::uint8_t* buffer, std::size_t size, int timeout_ms) override {
    std::size_t allowed = size;
    if (rate_ > 0) {
      const double elapsed =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
      const auto budget = static_cast<std::uint64_t>(elapsed * rate_);
      if (budget <= delivered_) {
        std::this_thread::sleep_for(std::chrono::milliseconds(std::min(timeout_ms, 5)));
        return 0;
      }
      allowed = std::min<std::size_t>(size, budget - delivered_);
    }
    in_.read(reinterpret_cast<char*>(buffer), static_cast<std::streamsize>(allowed));
    const auto n = static_cast<std::size_t>(in_.gcount());
    if (n == 0) throw CaptureEnded("capture file " + path_ + ": end of file");
    delivered_ += n;
    return n;
  }
  void write(std::string_view) override {}
  void discardInput() override {}
  bool acceptsCommands() const override { return false; }
  std::string describe() const override { return "capture file " + path_; }

 private:
  std::string path_;
  std::ifstream in_;
  double rate_;
  std::chrono::steady_clock::time_point start_;
  std::uint64_t delivered_ = 0;
};

}  // namespace

std::unique_ptr<Transport> openSerial(const SerialOptions& options) {
  struct stat st {};
  if (::stat(options.path.c_str(), &st) != 0) {
    throw std::runtime_error("no eDVS at " + options.path + ": the device node does not exist (" +
                             errnoText(errno) +
                             "); is the sensor plugged in and its FTDI bridge enumerated "
                             "(see `edvs_list_devices`, dmesg, the udev rule)?");
  }
  const int fd = ::open(options.path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    if (err == EACCES || err == EPERM) {
      throw std::runtime_error("cannot open " + options.path +
                               ": permission denied; add the user to the dialout group or "
                               "install edvs_driver/udev/99-edvs.rules");
    }
    throw std::runtime_error("cannot open " + options.path + ": " + errnoText(err));
  }
  Fd guard(fd);
  termios tio{};
  if (::tcgetattr(fd, &tio) != 0) {
    throw std::runtime_error(options.path +
                             " is not a serial port (tcgetattr: " + errnoText(errno) + ")");
  }
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | PARENB | CSIZE);
  tio.c_cflag |= CS8;
  if (options.rtscts) {
    tio.c_cflag |= CRTSCTS;
  } else {
    tio.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS);
  }
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  if (::tcsetattr(fd, TCSANOW, &tio) != 0) {
    throw std::runtime_error("cannot configure " + options.path + ": " + errnoText(errno));
  }
  if (!setSerialBaudRate(fd, options.baud)) {
    throw std::runtime_error("the serial driver of " + options.path + " refuses " +
                             std::to_string(options.baud) +
                             " baud; the eDVS runs at 2000000, 4000000 (standard), 6000000, "
                             "8000000 or 12000000 and the FTDI bridge must support the rate");
  }
  termios check{};
  ::tcgetattr(fd, &check);
  if (options.rtscts && !(check.c_cflag & CRTSCTS)) {
    throw std::runtime_error("the serial driver of " + options.path +
                             " does not support RTS/CTS flow control");
  }
  return std::make_unique<SerialTransport>(guard.release(), options);
}

std::unique_ptr<Transport> openTcp(const std::string& host, int port, int timeout_ms) {
  if (port <= 0 || port > 65535) {
    throw std::invalid_argument("TCP port " + std::to_string(port) + " outside 1..65535");
  }
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  const int gai = ::getaddrinfo(host.c_str(), service.c_str(), &hints, &found);
  if (gai != 0) {
    throw std::runtime_error("no eDVS at tcp://" + host + ":" + service + ": cannot resolve " +
                             host + " (" + ::gai_strerror(gai) + ")");
  }
  std::string last_error = "no address";
  for (addrinfo* a = found; a != nullptr; a = a->ai_next) {
    const int fd =
        ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
    if (fd < 0) continue;
    int r = ::connect(fd, a->ai_addr, a->ai_addrlen);
    if (r != 0 && errno == EINPROGRESS) {
      pollfd p{fd, POLLOUT, 0};
      r = ::poll(&p, 1, timeout_ms);
      if (r == 0) {
        last_error = "connection timed out after " + std::to_string(timeout_ms) + " ms";
        ::close(fd);
        continue;
      }
      int err = 0;
      socklen_t len = sizeof(err);
      ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len);
      r = err == 0 ? 0 : -1;
      errno = err;
    }
    if (r != 0) {
      last_error = errnoText(errno);
      ::close(fd);
      continue;
    }
    const int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    ::freeaddrinfo(found);
    return std::make_unique<TcpTransport>(fd, host + ":" + service);
  }
  ::freeaddrinfo(found);
  throw std::runtime_error("no eDVS at tcp://" + host + ":" + service + ": " + last_error +
                           " (is the WiFi module on and the address right?)");
}

std::unique_ptr<Transport> openCaptureFile(const std::string& path, double bytes_per_second) {
  return std::make_unique<CaptureFileTransport>(path, bytes_per_second);
}

}  // namespace edvs

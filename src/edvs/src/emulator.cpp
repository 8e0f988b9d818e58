#include "edvs/emulator.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <stdexcept>

#include "edvs/biases.h"

namespace edvs {

namespace {

using Clock = std::chrono::steady_clock;

std::int64_t microsSince(Clock::time_point origin, Clock::time_point now) {
  return std::chrono::duration_cast<std::chrono::microseconds>(now - origin).count();
}

constexpr const char* kBanner =
    "\r\nEDVS-4337 (emulated by edvs_driver), 128x128 DVS, firmware "
    "%s"
    "\r\n"
    "Type ?? for help.\r\n";

constexpr const char* kHelp =
    "R        reset\r\n"
    "!U0/!U1  echo off/on\r\n"
    "E+ / E-  start/stop event streaming\r\n"
    "!E0..!E4 event format (none, delta, 16, 24, 32 bit timestamp)\r\n"
    "!ET0     reset timestamp\r\n"
    "!ETM0/+  timestamp master stop/run, !ETS slave\r\n"
    "!B<n>=<v> set bias n, !BF flush biases (only while streaming)\r\n";

/// The generator behind generateEvents() and the emulator's default source.
class Generator {
 public:
  Generator(std::uint32_t seed, double rate_hz)
      : rng_(seed), coord_(0, 127), gap_(rate_hz > 0 ? rate_hz / 1e6 : 1.0) {}
  ebslam::Event next() {
    ebslam::Event e;
    e.t_us = t_;
    e.x = static_cast<std::uint16_t>(coord_(rng_));
    e.y = static_cast<std::uint16_t>(coord_(rng_));
    e.polarity = (rng_() & 1u) != 0;
    t_ += static_cast<std::int64_t>(std::llround(gap_(rng_)));
    return e;
  }

 private:
  std::mt19937 rng_;
  std::uniform_int_distribution<int> coord_;
  std::exponential_distribution<double> gap_;
  std::int64_t t_ = 0;
};

}  // namespace

ebslam::EventVector generateEvents(std::uint32_t seed, double rate_hz, std::size_t count) {
  if (!(rate_hz > 0)) throw std::invalid_argument("generator rate must be > 0 events/s");
  Generator g(seed, rate_hz);
  ebslam::EventVector out;
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i) out.push_back(g.next());
  return out;
}

struct Emulator::State {
  EmulatorConfig config;
  mutable std::mutex mutex;
  std::atomic<bool> stop{false};

  // Endpoint.
  int master_fd = -1;      // pty master, or connected TCP client
  int slave_keep_fd = -1;  // pty slave held open so settings persist and writes never fail
  int listen_fd = -1;
  int port = 0;
  std::string slave_path;
  bool present = true;
  Clock::time_point return_at{};
  bool return_pending = false;
  int appearances = 1;

  // Device state.
  bool echo = true;
  bool streaming = false;
  bool frozen = false;
  EventFormat format = EventFormat::kNone;
  Clock::time_point clock_origin = Clock::now();
  bool clock_held = false;
  Clock::time_point stall_until{};

  // Stream.
  std::unique_ptr<Generator> generator;
  std::size_t source_index = 0;             // next index into config.events
  std::int64_t loop_offset = 0;             // added to file times after each loop
  std::optional<ebslam::Event> next_event;  // next event of the source (source time)
  Clock::time_point segment_start{};
  std::int64_t segment_source_t0 = 0;  // source time of the segment's first event
  std::int64_t segment_device_t0 = 0;  // device time at segment start
  std::int64_t previous_device_t = 0;  // for the delta format
  bool previous_valid = false;
  std::uint64_t segment_bytes = 0;
  double line_credit_bytes = 0;         // line budget not available (time the line spent stalled)
  bool stalled = false;                 // a stall began and its end has not been seen yet
  std::vector<std::uint8_t> event_out;  // encoded events not yet written
  std::size_t event_out_pos = 0;
  std::string control_out;  // echo and replies, written between events
  std::string command_line;
  std::mt19937 garbage_rng;

  // Observations.
  std::vector<std::string> commands;
  std::vector<std::string> violations;
  ebslam::EventVector sent;
  std::uint64_t garbage_bytes = 0;
  std::size_t produced = 0;  // events taken from the source, cut ones included
  std::size_t cut = 0;       // events sent only in part

  explicit State(EmulatorConfig c) : config(std::move(c)), garbage_rng(config.seed ^ 0x9E3779B9u) {}

  std::int64_t deviceNow(Clock::time_point now) const {
    return clock_held ? 0 : microsSince(clock_origin, now);
  }

  bool sourceHasNext() {
    if (config.max_events > 0 && produced >= config.max_events) return false;
    if (next_event) return true;
    if (config.events.empty()) {
      next_event = generator->next();
      return true;
    }
    if (source_index >= config.events.size()) {
      if (!config.loop) return false;
      loop_offset += config.events.back().t_us - config.events.front().t_us + 1;
      source_index = 0;
    }
    ebslam::Event e = config.events[source_index++];
    e.t_us = e.t_us - config.events.front().t_us + loop_offset;
    next_event = e;
    return true;
  }

  void openPty() {
    master_fd = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master_fd < 0 || ::grantpt(master_fd) != 0 || ::unlockpt(master_fd) != 0) {
      throw std::runtime_error(std::string("emulator: cannot create a pseudo-terminal: ") +
                               std::strerror(errno));
    }
    char name[128];
    if (::ptsname_r(master_fd, name, sizeof(name)) != 0) {
      throw std::runtime_error("emulator: ptsname failed");
    }
    slave_path = name;
    slave_keep_fd = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (slave_keep_fd < 0) throw std::runtime_error("emulator: cannot open " + slave_path);
    termios tio{};
    ::tcgetattr(slave_keep_fd, &tio);
    ::cfmakeraw(&tio);  // no echo, no line editing: a byte pipe like a USB serial bridge
    ::tcsetattr(slave_keep_fd, TCSANOW, &tio);
    ::fcntl(master_fd, F_SETFL, ::fcntl(master_fd, F_GETFL) | O_NONBLOCK);
    ::fcntl(master_fd, F_SETFD, FD_CLOEXEC);
    if (!config.link_path.empty()) {
      const std::string tmp = config.link_path + ".tmp";
      ::unlink(tmp.c_str());
      if (::symlink(slave_path.c_str(), tmp.c_str()) != 0 ||
          ::rename(tmp.c_str(), config.link_path.c_str()) != 0) {
        throw std::runtime_error("emulator: cannot create link " + config.link_path + ": " +
                                 std::strerror(errno));
      }
    }
    // Leftovers of a previous session: a stream in another format, cut mid-event.
    if (config.stale_bytes > 0) {
      std::vector<std::uint8_t> stale;
      std::mt19937 rng(config.seed + 7u);
      while (stale.size() < config.stale_bytes) {
        ebslam::Event e;
        e.x = static_cast<std::uint16_t>(rng() % 128);
        e.y = static_cast<std::uint16_t>(rng() % 128);
        e.t_us = static_cast<std::int64_t>(rng() % 60000);
        encodeEvent(e, EventFormat::kAbs24, 0, 1, stale);
      }
      stale.resize(config.stale_bytes);
      if (::write(master_fd, stale.data(), stale.size()) < 0) {
        violations.push_back("emulator: could not pre-fill stale bytes");
      }
    }
  }

  void openTcp() {
    listen_fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (listen_fd < 0) throw std::runtime_error("emulator: socket failed");
    const int one = 1;
    ::setsockopt(listen_fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = htons(static_cast<std::uint16_t>(port));
    if (::bind(listen_fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 ||
        ::listen(listen_fd, 1) != 0) {
      throw std::runtime_error(std::string("emulator: cannot listen on 127.0.0.1:") +
                               std::to_string(port) + ": " + std::strerror(errno));
    }
    socklen_t len = sizeof(addr);
    ::getsockname(listen_fd, reinterpret_cast<sockaddr*>(&addr), &len);
    port = ntohs(addr.sin_port);
  }

  void appear() {
    if (config.tcp) {
      openTcp();
    } else {
      openPty();
    }
    present = true;
    resetDevice(Clock::now());
    streaming = false;
  }

  void closeAll() {
    for (int* fd : {&master_fd, &slave_keep_fd, &listen_fd}) {
      if (*fd >= 0) ::close(*fd);
      *fd = -1;
    }
    if (!config.tcp && !config.link_path.empty()) ::unlink(config.link_path.c_str());
  }

  void vanish(int return_after_ms) {
    closeAll();
    present = false;
    streaming = false;
    event_out.clear();
    event_out_pos = 0;
    control_out.clear();
    command_line.clear();
    return_pending = return_after_ms >= 0;
    return_at = Clock::now() + std::chrono::milliseconds(std::max(0, return_after_ms));
  }

  void resetDevice(Clock::time_point now) {
    echo = true;
    streaming = false;
    frozen = false;
    format = EventFormat::kNone;
    clock_origin = now;
    clock_held = false;
    event_out.clear();  // unsent event bytes are lost with the reset
    event_out_pos = 0;
    previous_valid = false;
  }

  void startSegment(Clock::time_point now) {
    segment_start = now;
    segment_bytes = 0;
    line_credit_bytes = 0;
    if (sourceHasNext()) segment_source_t0 = next_event->t_us;
    segment_device_t0 = deviceNow(now);
    previous_valid = false;
  }

  void handleCommand(const std::string& line, Clock::time_point now) {
    commands.push_back(line);
    if (frozen && line != "R") return;  // a frozen camera only recovers with a reset
    auto reply = [&](const std::string& text) { control_out += text; };
    if (line == "R") {
      resetDevice(now);
      char banner[256];
      std::snprintf(banner, sizeof(banner), kBanner, toString(config.firmware));
      reply(banner);
    } else if (line == "!U0") {
      echo = false;
    } else if (line == "!U1") {
      echo = true;
    } else if (line == "E+") {
      if (!streaming) {
        streaming = true;
        startSegment(now);
      }
    } else if (line == "E-") {
      streaming = false;
    } else if (line == "??") {
      reply(kHelp);
    } else if (line == "!ET0") {
      clock_origin = now;
    } else if (line == "!ETM0") {
      clock_held = true;
    } else if (line == "!ETM+") {
      clock_held = false;
      clock_origin = now;
    } else if (line == "!ETS") {
      // Slave: the clock would come from the master's sync line; the emulator keeps its own.
    } else if (line.size() == 3 && line.rfind("!E", 0) == 0) {
      const auto f = formatFromCommandNumber(line[2] - '0', config.firmware);
      if (!f) {
        violations.push_back("unknown event format command " + line + " for " +
                             toString(config.firmware) + " firmware");
        reply("?\r\n");
      } else {
        format = *f;
        previous_valid = false;
      }
    } else if (line.rfind("!B", 0) == 0) {
      if (!streaming) {
        violations.push_back("bias command while not streaming: " + line +
                             " (a real eDVS freezes)");
        frozen = true;
        return;
      }
      if (line != "!BF") {
        const auto eq = line.find('=');
        bool ok = eq != std::string::npos && eq > 2;
        if (ok) {
          char* end = nullptr;
          const long idx = std::strtol(line.c_str() + 2, &end, 10);
          ok = end == line.c_str() + eq && idx >= 0 && idx < kNumBiases;
          const long long v = std::strtoll(line.c_str() + eq + 1, &end, 10);
          ok = ok && *end == '\0' && v >= 0 && v <= 0xFFFFFF;
        }
        if (!ok) {
          violations.push_back("malformed bias command " + line);
          reply("?\r\n");
        }
      }
    } else if (!line.empty()) {
      violations.push_back("unknown command " + line);
      reply("?\r\n");
    }
  }

  void handleInput(const char* data, std::size_t n, Clock::time_point now) {
    if (echo && !frozen) control_out.append(data, n);
    for (std::size_t i = 0; i < n; ++i) {
      const char c = data[i];
      if (c == '\n') {
        handleCommand(command_line, now);
        command_line.clear();
      } else if (c != '\r' && command_line.size() < 256) {
        command_line.push_back(c);
      }
    }
  }

  void produceEvents(Clock::time_point now) {
    if (!streaming || frozen || now < stall_until) return;
    const std::int64_t elapsed_us = microsSince(segment_start, now);
    if (stalled) {
      stalled = false;
      if (config.stall_drains_at_line_rate && config.line_bytes_per_second > 0) {
        // The budget the line did not use while stalled is gone: the backlog drains at the rate.
        const double budget = config.line_bytes_per_second * elapsed_us * 1e-6 + 64;
        line_credit_bytes = std::max(0.0, budget - static_cast<double>(segment_bytes));
      }
    }
    if (event_out.size() - event_out_pos > 65536) return;  // the line is backed up
    const double speed = config.speed > 0 ? config.speed : 1.0;
    while (sourceHasNext()) {
      const std::int64_t offset = next_event->t_us - segment_source_t0;
      const auto play_offset = static_cast<std::int64_t>(std::llround(offset / speed));
      if (play_offset > elapsed_us) break;
      if (config.line_bytes_per_second > 0) {
        const double budget =
            config.line_bytes_per_second * elapsed_us * 1e-6 + 64 - line_credit_bytes;
        if (static_cast<double>(segment_bytes) >= budget) break;
      }
      ebslam::Event e = *next_event;
      next_event.reset();
      e.t_us = segment_device_t0 + play_offset;
      if (config.garbage_probability > 0 &&
          std::uniform_real_distribution<double>(0, 1)(garbage_rng) < config.garbage_probability) {
        const int n = 1 + static_cast<int>(garbage_rng() % 8);
        for (int k = 0; k < n; ++k) {
          event_out.push_back(static_cast<std::uint8_t>(garbage_rng()));
        }
        garbage_bytes += static_cast<std::uint64_t>(n);
        segment_bytes += static_cast<std::uint64_t>(n);
      }
      const std::size_t before = event_out.size();
      encodeEvent(e, format, previous_valid ? previous_device_t : e.t_us, config.on_bit, event_out);
      const bool cut_here =
          std::binary_search(config.cut_events.begin(), config.cut_events.end(), produced);
      ++produced;
      if (cut_here) {
        // Only the first 1..n-1 bytes of this event reach the line.
        const std::size_t n = event_out.size() - before;
        event_out.resize(before + 1 + garbage_rng() % (n - 1));
        ++cut;
      }
      segment_bytes += event_out.size() - before;
      previous_device_t = e.t_us;
      previous_valid = true;
      if (cut_here) continue;
      sent.push_back(e);
      if (config.stall_after_events && sent.size() == *config.stall_after_events) {
        stall_until = now + std::chrono::milliseconds(config.stall_ms);
        stalled = true;
        break;
      }
      if (config.vanish_after_events && sent.size() == *config.vanish_after_events) {
        flushEvents();
        vanish(config.return_after_ms);
        return;
      }
    }
  }

  void flushEvents() {
    while (master_fd >= 0 && event_out_pos < event_out.size()) {
      const ssize_t n =
          ::write(master_fd, event_out.data() + event_out_pos, event_out.size() - event_out_pos);
      if (n <= 0) break;
      event_out_pos += static_cast<std::size_t>(n);
    }
    if (event_out_pos == event_out.size()) {
      event_out.clear();
      event_out_pos = 0;
    }
  }

  void flushControl() {
    // Replies go out only at event boundaries, never inside an event.
    if (master_fd < 0 || control_out.empty() || event_out_pos != 0 || !event_out.empty()) return;
    const ssize_t n = ::write(master_fd, control_out.data(), control_out.size());
    if (n > 0) control_out.erase(0, static_cast<std::size_t>(n));
  }
};

Emulator::Emulator(EmulatorConfig config) : state_(std::make_unique<State>(std::move(config))) {
  State& s = *state_;
  if (s.config.on_bit != 0 && s.config.on_bit != 1) {
    throw std::invalid_argument("EmulatorConfig::on_bit must be 0 or 1");
  }
  std::sort(s.config.cut_events.begin(), s.config.cut_events.end());
  if (s.config.events.empty() && !(s.config.rate_hz > 0)) {
    throw std::invalid_argument("EmulatorConfig::rate_hz must be > 0 for the generator");
  }
  for (std::size_t i = 0; i < s.config.events.size(); ++i) {
    const ebslam::Event& e = s.config.events[i];
    if (e.x > 127 || e.y > 127) {
      throw std::invalid_argument("emulator events must lie inside 128 x 128 (event " +
                                  std::to_string(i) + ")");
    }
    if (i > 0 && e.t_us < s.config.events[i - 1].t_us) {
      throw std::invalid_argument("emulator events must be sorted by time (event " +
                                  std::to_string(i) + ")");
    }
  }
  s.generator = std::make_unique<Generator>(s.config.seed, s.config.rate_hz);
  s.port = s.config.tcp_port;
  s.appear();
  thread_ = std::thread([this] { run(); });
}

Emulator::~Emulator() {
  state_->stop = true;
  if (thread_.joinable()) thread_.join();
  state_->closeAll();
}

void Emulator::run() {
  State& s = *state_;
  char buffer[1024];
  while (!s.stop) {
    const Clock::time_point now = Clock::now();
    std::unique_lock<std::mutex> lock(s.mutex);
    if (!s.present) {
      if (s.return_pending && now >= s.return_at) {
        s.return_pending = false;
        try {
          s.appear();
          ++s.appearances;
        } catch (const std::exception& e) {
          s.violations.push_back(std::string("emulator could not reappear: ") + e.what());
        }
      }
      lock.unlock();
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      continue;
    }
    if (s.config.tcp && s.master_fd < 0) {
      const int fd = ::accept4(s.listen_fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd >= 0) {
        s.master_fd = fd;
      } else {
        lock.unlock();
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        continue;
      }
    }
    const ssize_t n = ::read(s.master_fd, buffer, sizeof(buffer));
    if (n > 0) {
      s.handleInput(buffer, static_cast<std::size_t>(n), now);
    } else if (s.config.tcp && n == 0) {
      // The client hung up; the module keeps running and waits for the next one.
      ::close(s.master_fd);
      s.master_fd = -1;
      s.streaming = false;
      s.event_out.clear();
      s.event_out_pos = 0;
      s.control_out.clear();
    }
    if (s.present && s.master_fd >= 0) {
      s.flushControl();
      s.produceEvents(now);
      if (s.present) {
        s.flushEvents();
        s.flushControl();
      }
    }
    const int fd = s.master_fd;
    const bool want_out = !s.event_out.empty() || !s.control_out.empty();
    lock.unlock();
    if (fd >= 0) {
      pollfd p{fd, static_cast<short>(POLLIN | (want_out ? POLLOUT : 0)), 0};
      ::poll(&p, 1, 1);
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
}

std::string Emulator::devicePath() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->config.link_path.empty() ? state_->slave_path : state_->config.link_path;
}

std::string Emulator::uri() const {
  if (state_->config.tcp) return "tcp://127.0.0.1:" + std::to_string(tcpPort());
  return "serial://" + devicePath();
}

int Emulator::tcpPort() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->port;
}

void Emulator::vanish(int return_after_ms) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  if (state_->present) state_->vanish(return_after_ms);
}

void Emulator::stall(int ms) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->stall_until = Clock::now() + std::chrono::milliseconds(ms);
  state_->stalled = true;
}

std::vector<std::string> Emulator::commands() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->commands;
}

std::vector<std::string> Emulator::violations() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->violations;
}

ebslam::EventVector Emulator::sentEvents() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->sent;
}

std::size_t Emulator::eventsSent() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->sent.size();
}

std::size_t Emulator::eventsCut() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->cut;
}

std::uint64_t Emulator::garbageBytesSent() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->garbage_bytes;
}

bool Emulator::streaming() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->streaming;
}

EventFormat Emulator::format() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->format;
}

int Emulator::appearances() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->appearances;
}

}  // namespace edvs

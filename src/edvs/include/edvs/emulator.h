#pragma once

// An emulated eDVS4337 on a pseudo-terminal (or a loopback TCP port): answers the ASCII
// commands and streams events in the selected format at a chosen rate, with injectable faults
// (garbage bytes, stalls, vanishing mid-stream, stale bytes at open). ROS-free.

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "ebslam/events/event.h"
#include "edvs/event_encoder.h"  // the device side: what it sends, tests encode alike
#include "edvs/event_format.h"

namespace edvs {

/// Events of the seeded generator: uniform pixels and polarities, exponential inter-event times
/// with mean 1e6 / rate_hz microseconds, the first at t = 0. Deterministic for a seed, so a test
/// can regenerate exactly what the emulator streamed.
ebslam::EventVector generateEvents(std::uint32_t seed, double rate_hz, std::size_t count);

struct EmulatorConfig {
  Firmware firmware = Firmware::kCurrent;
  /// Events to stream (times in us; streamed relative to the first). Empty: the generator.
  ebslam::EventVector events;
  bool loop = false;           ///< restart `events` from the beginning when they run out
  std::uint32_t seed = 1;      ///< generator seed
  double rate_hz = 10000.0;    ///< generator event rate [events/s]
  std::size_t max_events = 0;  ///< stop streaming after this many events (0 = no limit)
  /// Playback speed of `events` relative to real time (1 = as recorded); device timestamps
  /// follow the playback clock.
  double speed = 1.0;
  /// Line rate limit [bytes/s]; 4 Mbit/s 8N1 carries 400000 bytes/s. 0 = unlimited.
  double line_bytes_per_second = 400000.0;
  int on_bit = 1;  ///< polarity bit value written for ON events

  // Faults.
  double garbage_probability = 0.0;  ///< per event: insert 1..8 random bytes before it
  /// Indices (0-based, in streaming order) of events cut in the middle: only their first
  /// 1..n-1 bytes are sent (a glitch on the line); they are not in sentEvents().
  std::vector<std::size_t> cut_events;
  std::size_t stale_bytes = 0;  ///< bytes of an old stream waiting when the host opens
  std::optional<std::size_t> stall_after_events;  ///< stop sending after this many events...
  int stall_ms = 0;                               ///< ...for this long, then continue
  /// After a stall the device's clock has run on and its events are queued: false sends the
  /// whole backlog at once (as a writer that held its bytes), true drains it at the line rate
  /// (as a serial line does; needs line_bytes_per_second > 0).
  bool stall_drains_at_line_rate = false;
  std::optional<std::size_t> vanish_after_events;  ///< close the device after this many events
  int return_after_ms = -1;  ///< reappear (new pty, same link) after this long; -1 = never

  /// Symlink kept pointing at the current pty slave (like a udev symlink); empty = none.
  std::string link_path;
  /// Serve TCP on 127.0.0.1 instead of a pty; port 0 picks a free port.
  bool tcp = false;
  int tcp_port = 0;
};

/// One emulated device. Thread-safe observers; all I/O runs on an internal thread.
class Emulator {
 public:
  /// Creates the pty (or listening socket) and starts the device thread. Throws
  /// std::runtime_error if the pty or socket cannot be created, std::invalid_argument for
  /// an invalid config.
  explicit Emulator(EmulatorConfig config);
  ~Emulator();
  Emulator(const Emulator&) = delete;
  Emulator& operator=(const Emulator&) = delete;

  /// Path a host opens: the link if configured, else the pty slave.
  std::string devicePath() const;
  /// The URI of this device ("serial://<path>" or "tcp://127.0.0.1:<port>").
  std::string uri() const;
  int tcpPort() const;

  /// Makes the device disappear now (as unplugging) and, if return_after_ms >= 0, reappear.
  void vanish(int return_after_ms);
  /// Stops sending for `ms` milliseconds.
  void stall(int ms);

  // Observations.
  std::vector<std::string> commands() const;    ///< command lines received, in order
  std::vector<std::string> violations() const;  ///< protocol misuse seen (see below)
  /// Events sent on the wire with their full 64-bit device time [us], in order.
  ebslam::EventVector sentEvents() const;
  std::size_t eventsSent() const;
  std::uint64_t garbageBytesSent() const;
  std::size_t eventsCut() const;  ///< events sent only in part (cut_events reached so far)
  bool streaming() const;
  EventFormat format() const;
  int appearances() const;  ///< 1 + number of times it came back after vanishing

 private:
  struct State;
  void run();
  std::unique_ptr<State> state_;
  std::thread thread_;
};

}  // namespace edvs

#pragma once

// Keeps an eDVS streaming on a thread of its own: opens the device, retries a failed open with
// exponential backoff, reopens after a loss or a stall, and stamps the events on one published
// clock that never runs backwards, not even across reconnects (ebslam::EventClock, anchored once
// per stream). ROS-free: the owner publishes the events and reports status(); nothing is logged.

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "ebslam/events/event.h"
#include "ebslam/events/event_clock.h"
#include "edvs/device.h"

namespace edvs {

struct SupervisorConfig {
  double reconnect_min_s = 0.5;    ///< first retry delay, also after a lost device [s]
  double reconnect_max_s = 8.0;    ///< cap of the delay, which doubles per failed open [s]
  double stall_reconnect_s = 5.0;  ///< no bytes this long while streaming: reopen [s]
  int read_timeout_ms = 20;        ///< wait of one read for bytes [ms]
  /// Bias values (index 0..11, 24 bit) sent at every open; nullopt keeps the device's own.
  std::array<std::optional<std::int64_t>, kNumBiases> biases{};
};

enum class LinkState { kConnecting, kStreaming, kDisconnected, kCaptureEnded };

/// What happened on the link, for the owner's log.
enum class LinkEvent {
  kOpenFailed,    ///< an open failed; retried after the backoff delay
  kConnected,     ///< the first stream started
  kReconnected,   ///< a later stream started
  kCaptureEnded,  ///< a capture file was read to its end
  kLost,          ///< the device went away while streaming
  kStalled,       ///< no bytes for stall_reconnect_s: the device is reopened
};

/// A snapshot of the link for diagnostics.
struct LinkStatus {
  LinkState state = LinkState::kDisconnected;
  std::string last_error;       ///< why the last open failed or the last stream ended
  std::string last_disconnect;  ///< why the last working stream ended
  std::uint64_t connects = 0;   ///< successful opens
  std::uint64_t failed_attempts = 0;
  std::uint64_t disconnects = 0;  ///< streams that ended other than at a capture's end
  DeviceStats stats;              ///< of the device, cumulative over reconnects
  std::string banner;             ///< reset banner of the last open
  bool format_suspect = false;    ///< see EventParser::formatSuspect
  std::int64_t last_data_us = 0;  ///< monotonicMicros() of the last bytes (or of the open)
  std::uint64_t events = 0;       ///< events delivered to the sink
  std::uint64_t reconnects() const { return connects > 0 ? connects - 1 : 0; }
};

class LinkSupervisor {
 public:
  struct Callbacks {
    /// Events of one read, stamped on the published clock, in order; on the worker thread.
    std::function<void(ebslam::EventVector& events)> on_events;
    /// After a stream ended and the device was closed (flush what waits); worker thread.
    std::function<void()> on_stream_end;
    /// A link event with its message; on the worker thread.
    std::function<void(LinkEvent event, const std::string& message)> on_log;
    /// Published time now [us], taken as the anchor of each stream; default: system clock
    /// since the epoch. (The driver nodelet passes ROS time.)
    std::function<std::int64_t()> now_us;
  };

  /// Throws std::invalid_argument for a bad device or supervisor config. The factory is
  /// EdvsDevice's (tests inject their own transports).
  LinkSupervisor(DeviceConfig device, SupervisorConfig config, Callbacks callbacks,
                 EdvsDevice::TransportFactory factory = {});
  ~LinkSupervisor();
  LinkSupervisor(const LinkSupervisor&) = delete;
  LinkSupervisor& operator=(const LinkSupervisor&) = delete;

  /// Starts the worker thread: the first open is attempted at once.
  void start();
  /// Stops and joins the worker thread (an open in progress finishes first). Idempotent.
  void stop();

  /// Sets a bias (index 0..11, 24 bit) if it differs from the value held; the device gets it
  /// while streaming (see EdvsDevice::setBias) and again at every later open.
  void setBias(int index, std::int64_t value);
  LinkStatus status() const;

 private:
  using SteadyTime = std::chrono::steady_clock::time_point;

  void worker();
  bool waitForAttempt();
  bool connect();
  void readLoop();
  bool afterStream();
  void stampAndDeliver(ebslam::EventVector& batch);
  void log(LinkEvent event, const std::string& message) const;

  SupervisorConfig config_;
  Callbacks callbacks_;
  std::unique_ptr<EdvsDevice> device_;  // worker thread only (once started)
  ebslam::EventClock clock_;            // worker thread only: device time -> published time
  std::thread worker_;
  std::atomic<bool> stop_{false};

  mutable std::mutex mutex_;  // guards everything below
  std::condition_variable wake_;
  LinkStatus status_;
  SteadyTime next_attempt_{};
  double backoff_s_ = 0.0;
  bool capture_ended_ = false;  // the capture file was read to its end
  std::array<std::optional<std::int64_t>, kNumBiases> biases_{};
  std::vector<std::pair<int, std::int64_t>> bias_changes_;  // sent by the worker
};

}  // namespace edvs

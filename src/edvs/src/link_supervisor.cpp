#include "edvs/link_supervisor.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace edvs {

namespace {

std::int64_t systemMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(s));
}

}  // namespace

LinkSupervisor::LinkSupervisor(DeviceConfig device, SupervisorConfig config, Callbacks callbacks,
                               EdvsDevice::TransportFactory factory)
    : config_(std::move(config)), callbacks_(std::move(callbacks)) {
  if (!(config_.reconnect_min_s > 0)) {
    throw std::invalid_argument("SupervisorConfig: reconnect_min_s must be > 0 s");
  }
  if (!(config_.reconnect_max_s >= config_.reconnect_min_s)) {
    throw std::invalid_argument("SupervisorConfig: reconnect_max_s must be >= reconnect_min_s");
  }
  if (!(config_.stall_reconnect_s > 0)) {
    throw std::invalid_argument("SupervisorConfig: stall_reconnect_s must be > 0 s");
  }
  if (config_.read_timeout_ms < 0) {
    throw std::invalid_argument("SupervisorConfig: read_timeout_ms must be >= 0");
  }
  for (int i = 0; i < kNumBiases; ++i) {
    const auto& v = config_.biases[static_cast<std::size_t>(i)];
    if (v) commands::setBias(i, *v);  // validates
  }
  if (!callbacks_.now_us) callbacks_.now_us = systemMicros;
  device_ = std::make_unique<EdvsDevice>(std::move(device), std::move(factory));
  biases_ = config_.biases;
  backoff_s_ = config_.reconnect_min_s;
}

LinkSupervisor::~LinkSupervisor() { stop(); }

void LinkSupervisor::start() {
  if (worker_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    next_attempt_ = std::chrono::steady_clock::now();
  }
  stop_ = false;
  worker_ = std::thread([this] { worker(); });
}

void LinkSupervisor::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void LinkSupervisor::setBias(int index, std::int64_t value) {
  commands::setBias(index, value);  // validates
  std::lock_guard<std::mutex> lock(mutex_);
  auto& current = biases_[static_cast<std::size_t>(index)];
  if (current && *current == value) return;
  current = value;
  bias_changes_.emplace_back(index, value);  // the worker sends it while streaming
}

LinkStatus LinkSupervisor::status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return status_;
}

void LinkSupervisor::log(LinkEvent event, const std::string& message) const {
  if (callbacks_.on_log) callbacks_.on_log(event, message);
}

void LinkSupervisor::worker() {
  while (!stop_) {
    if (!waitForAttempt()) break;
    if (!connect()) continue;
    readLoop();
    device_->close();
    if (callbacks_.on_stream_end) callbacks_.on_stream_end();
    if (!afterStream()) break;
  }
  device_->close();
}

bool LinkSupervisor::waitForAttempt() {
  std::unique_lock<std::mutex> lock(mutex_);
  wake_.wait_until(lock, next_attempt_, [this] { return stop_.load(); });
  if (stop_) return false;
  status_.state = LinkState::kConnecting;
  return true;
}

bool LinkSupervisor::connect() {
  std::array<std::optional<std::int64_t>, kNumBiases> biases;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    biases = biases_;
    bias_changes_.clear();
  }
  try {
    for (int i = 0; i < kNumBiases; ++i) {
      // Remembered by the device and sent only once it streams.
      if (const auto& v = biases[static_cast<std::size_t>(i)]) device_->setBias(i, *v);
    }
    device_->open();
    device_->start();
  } catch (const std::exception& e) {
    device_->close();
    double delay_s = 0.0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      status_.last_error = e.what();
      ++status_.failed_attempts;
      status_.state = LinkState::kDisconnected;
      delay_s = backoff_s_;
      next_attempt_ = std::chrono::steady_clock::now() + seconds(delay_s);
      backoff_s_ = std::min(backoff_s_ * 2.0, config_.reconnect_max_s);
    }
    char retry[48];
    std::snprintf(retry, sizeof(retry), " (retrying in %.1f s)", delay_s);
    log(LinkEvent::kOpenFailed, e.what() + std::string(retry));
    return false;
  }
  std::uint64_t connects = 0;
  std::string banner = device_->banner();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    connects = ++status_.connects;
    status_.state = LinkState::kStreaming;
    status_.banner = banner;
    status_.last_data_us = monotonicMicros();
  }
  clock_.unanchor();  // a new stream gets a new anchor
  if (connects > 1) {
    log(LinkEvent::kReconnected, "reconnected to " + device_->describe() + " (reconnect " +
                                     std::to_string(connects - 1) + ")");
  } else {
    log(LinkEvent::kConnected, "streaming from " + device_->describe() + " (" + banner + ")");
  }
  return true;
}

void LinkSupervisor::readLoop() {
  ebslam::EventVector batch;
  std::uint64_t bytes_seen = device_->stats().bytes_read;
  while (!stop_) {
    std::vector<std::pair<int, std::int64_t>> changes;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      changes.swap(bias_changes_);
    }
    batch.clear();
    try {
      for (const auto& [index, value] : changes) device_->setBias(index, value);
      device_->read(batch, config_.read_timeout_ms);
    } catch (const CaptureEnded& e) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        capture_ended_ = true;
      }
      log(LinkEvent::kCaptureEnded,
          e.what() + std::string(device_->uri().file_loop ? ": replaying it again (loop=1)" : ""));
      return;
    } catch (const std::exception& e) {
      const std::string error = std::string("device lost: ") + e.what();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        status_.last_error = error;
        status_.last_disconnect = error;
      }
      log(LinkEvent::kLost, error);
      return;
    }
    const std::int64_t now = monotonicMicros();
    const DeviceStats& stats = device_->stats();
    std::string stalled;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stats.bytes_read != bytes_seen) {
        bytes_seen = stats.bytes_read;
        status_.last_data_us = now;
      }
      status_.stats = stats;
      status_.format_suspect = device_->formatSuspect();
      if (now - status_.last_data_us > static_cast<std::int64_t>(config_.stall_reconnect_s * 1e6)) {
        stalled =
            "no data for " + std::to_string(config_.stall_reconnect_s) + " s: reopening the device";
        status_.last_error = stalled;
        status_.last_disconnect = stalled;
      }
    }
    if (!stalled.empty()) {
      log(LinkEvent::kStalled, stalled);
      return;
    }
    if (!batch.empty()) stampAndDeliver(batch);
  }
}

bool LinkSupervisor::afterStream() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (capture_ended_) {
    capture_ended_ = false;
    if (!device_->uri().file_loop) {
      // A capture ends at its end: nothing to reconnect to.
      status_.state = LinkState::kCaptureEnded;
      return false;
    }
    status_.state = LinkState::kConnecting;  // loop=1: replay at once
    next_attempt_ = std::chrono::steady_clock::now();
    return true;
  }
  ++status_.disconnects;
  status_.state = LinkState::kDisconnected;
  backoff_s_ = config_.reconnect_min_s;  // a device that was there is retried soon
  next_attempt_ = std::chrono::steady_clock::now() + seconds(backoff_s_);
  return true;
}

void LinkSupervisor::stampAndDeliver(ebslam::EventVector& batch) {
  if (!clock_.anchored()) {
    // Once per stream: this read's published time is the time of the stream's first event.
    clock_.anchor(batch.front().t_us, callbacks_.now_us());
  }
  for (ebslam::Event& e : batch) {
    // The parser's 64-bit device clock starts near 0: no overflow in practice; were there one,
    // the event keeps the previous stamp rather than a wrapped one.
    const std::optional<std::int64_t> stamp = clock_.stamp(e.t_us);
    e.t_us = stamp ? *stamp : clock_.lastStamp().value_or(clock_.anchorPublished());
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    status_.events += batch.size();
  }
  if (callbacks_.on_events) callbacks_.on_events(batch);
}

}  // namespace edvs

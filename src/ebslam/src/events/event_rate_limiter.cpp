#include "ebslam/events/event_rate_limiter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ebslam {

void EventRateLimiterConfig::validate() const {
  if (!std::isfinite(max_rate_eps) || max_rate_eps < 0.0 ||
      (max_rate_eps > 0.0 && max_rate_eps < 1000.0)) {
    throw std::invalid_argument(
        "EventRateLimiterConfig::max_rate_eps must be 0 (no cap) or at least 1000 events/s, not " +
        std::to_string(max_rate_eps));
  }
  if (window_us < 100 || window_us > 1000000) {
    throw std::invalid_argument("EventRateLimiterConfig::window_us must be in [100, 1e6] us, not " +
                                std::to_string(window_us));
  }
}

EventRateLimiter::EventRateLimiter(const EventRateLimiterConfig& config) : config_(config) {
  config_.validate();
  reset();
}

void EventRateLimiter::reset() {
  state_ = config_.seed;
  started_ = false;
  window_ = 0;
  window_count_ = window_kept_ = 0;
  window_budget_ = 0;
  keep_threshold_ = kAlways;
  measured_rate_eps_ = 0.0;
  keep_probability_ = 1.0;
}

void EventRateLimiter::advanceTo(std::int64_t window) {
  const double window_s = 1e-6 * static_cast<double>(config_.window_us);
  if (started_) {
    // A pause spreads the last window's events over every window since.
    const double elapsed_s = static_cast<double>(window - window_) * window_s;
    measured_rate_eps_ = static_cast<double>(window_count_) / elapsed_s;
  }
  started_ = true;
  window_ = window;
  window_count_ = 0;
  window_kept_ = 0;
  window_budget_ =
      std::max<std::uint64_t>(1, static_cast<std::uint64_t>(2.0 * config_.max_rate_eps * window_s));
  if (measured_rate_eps_ <= config_.max_rate_eps) {
    keep_probability_ = 1.0;
    keep_threshold_ = kAlways;
  } else {
    keep_probability_ = config_.max_rate_eps / measured_rate_eps_;
    // p < 1, so p * 2^64 < 2^64 (an event is kept when the 64-bit draw is below it).
    keep_threshold_ = static_cast<std::uint64_t>(std::ldexp(keep_probability_, 64));
  }
}

}  // namespace ebslam

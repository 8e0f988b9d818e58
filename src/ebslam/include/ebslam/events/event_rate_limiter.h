#pragma once

// Rate cap for the pose filters (EB-PF, EB-SLAM-2D, EB-SLAM-3D): a sensor at 1-50 M events/s
// (DAVIS346, Prophesee 1280x720 in a lit room) would make a filter that keeps up with a few
// M events/s fall behind. Above `max_rate_eps` the limiter keeps every event with probability
// max_rate_eps / measured rate (uniform thinning: the kept events are an unbiased sample of the
// stream in space, time and polarity), drawn from a seeded generator, so a run is reproducible.
// The rate is measured in event time (the sensor's clock, not the wall clock) over windows of
// `window_us` aligned to multiples of window_us: the decisions depend only on the events and
// the seed, not on how the stream is cut into messages (a node and the core library given the
// same events keep the same ones). A burst is followed within one window; within that window
// at most 2 x max_rate_eps x window are kept, so a sudden jump of the rate cannot push more
// than twice the cap into the filter. Below the cap nothing is dropped and no random number is
// drawn. Details: docs/ebslam_core.md#event-rate-limiter

#include <cstddef>
#include <cstdint>
#include <vector>

namespace ebslam {

struct EventRateLimiterConfig {
  /// Largest event rate passed on [events per second of event time]; 0 = no cap.
  double max_rate_eps = 0.0;
  /// Length of the windows the rate is measured over [us of event time], >= 100.
  std::int64_t window_us = 2000;
  /// Seed of the thinning's random draws.
  std::uint64_t seed = 1;

  bool enabled() const { return max_rate_eps > 0.0; }
  /// Throws std::invalid_argument naming the offending field (max_rate_eps negative or not
  /// finite, or between 0 and 1000 events/s exclusive; window_us < 100 or > 1 s).
  void validate() const;
};

/// Uniform, seeded thinning of an event stream above a rate (see the file comment). Not
/// thread-safe; one per event stream.
class EventRateLimiter {
 public:
  /// Throws std::invalid_argument for an invalid config.
  explicit EventRateLimiter(const EventRateLimiterConfig& config);

  /// Whether the event at `t_us` (non-decreasing within a stream; an earlier time is treated as
  /// the current window) is kept.
  bool keep(std::int64_t t_us) {
    ++seen_;
    if (!config_.enabled()) {
      ++kept_;
      return true;
    }
    const std::int64_t window = floorDiv(t_us, config_.window_us);
    if (window > window_ || !started_) advanceTo(window);
    ++window_count_;
    if (window_kept_ >= window_budget_) return false;
    if (keep_threshold_ != kAlways && nextRandom() >= keep_threshold_) return false;
    ++window_kept_;
    ++kept_;
    return true;
  }

  /// Keeps the events of `events` (any type with a member t_us, in time order) that keep()
  /// accepts, in order; returns how many were dropped.
  template <typename EventT>
  std::size_t thinInPlace(std::vector<EventT>& events) {
    if (!config_.enabled()) {
      seen_ += events.size();
      kept_ += events.size();
      return 0;
    }
    std::size_t out = 0;
    for (std::size_t i = 0; i < events.size(); ++i) {
      if (keep(events[i].t_us)) {
        if (out != i) events[out] = events[i];
        ++out;
      }
    }
    const std::size_t dropped = events.size() - out;
    events.resize(out);
    return dropped;
  }

  /// Starts over (a restarted stream): rate, window and the random sequence from the seed.
  void reset();

  const EventRateLimiterConfig& config() const { return config_; }
  /// Events given to keep() / thinInPlace() since the start or reset().
  std::uint64_t seen() const { return seen_; }
  /// Events kept of them.
  std::uint64_t kept() const { return kept_; }
  /// The stream's rate measured over the last complete window(s) [events/s of event time].
  double measuredRate() const { return measured_rate_eps_; }
  /// Probability with which an event is kept now (1 below the cap).
  double keepProbability() const { return keep_probability_; }

 private:
  static constexpr std::uint64_t kAlways = ~std::uint64_t{0};

  static std::int64_t floorDiv(std::int64_t a, std::int64_t b) {
    const std::int64_t q = a / b;
    return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
  }
  /// splitmix64: fast, and good enough for Bernoulli draws.
  std::uint64_t nextRandom() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  /// Closes the current window and opens `window`: the rate and the keep probability.
  void advanceTo(std::int64_t window);

  EventRateLimiterConfig config_;
  std::uint64_t state_ = 0;
  std::int64_t window_ = 0;
  bool started_ = false;
  std::uint64_t window_count_ = 0, window_kept_ = 0, window_budget_ = 0;
  std::uint64_t keep_threshold_ = kAlways;
  double measured_rate_eps_ = 0.0, keep_probability_ = 1.0;
  std::uint64_t seen_ = 0, kept_ = 0;
};

}  // namespace ebslam

#pragma once

// Background-activity filter of event vision (Delbruck 2008; jAER's BackgroundActivityFilter and
// SpatioTemporalCorrelationFilter): an event passes when at least `min_support` of its 8
// neighbouring pixels fired within `window_us` before it (optionally only events of its own
// polarity); optionally a per-pixel refractory filter. O(1) per event. Why a support count and
// polarity, and the data layout: docs/ebslam_core.md#background-activity-filter

#include <cstddef>
#include <cstdint>
#include <vector>

#include "ebslam/events/event.h"

namespace ebslam {

struct BackgroundActivityFilterConfig {
  /// Support window [us]: only neighbour events at most this long before an event count.
  /// Defaults chosen for slow floor robots: docs/ebslam_core.md#background-activity-defaults
  std::int64_t window_us = 100000;
  /// Number of neighbouring pixels that must have fired within the window, in [1, 8].
  int min_support = 3;
  /// Count only neighbour events of the event's own polarity.
  bool polarity_match = true;
  /// Also run the per-pixel refractory filter.
  bool refractory_filter = false;
  /// Refractory period [us]: with refractory_filter, an event within this time after the same
  /// pixel's previous event (of either polarity, passed or not) is dropped. The eDVS' own dead
  /// time is about 100 us; 1 ms cuts the bursts of hot pixels.
  std::int64_t refractory_period_us = 1000;

  /// Throws std::invalid_argument naming the offending parameter (window_us <= 0, min_support
  /// outside [1, 8], refractory_period_us < 0).
  void validate() const;
};

/// How well a filter separates signal from noise against ground-truth labels (1 = noise).
struct DenoisingScore {
  std::size_t signal = 0, signal_kept = 0;
  std::size_t noise = 0, noise_removed = 0;
  double signalKeptFraction() const { return signal ? double(signal_kept) / signal : 1.0; }
  double noiseRemovedFraction() const { return noise ? double(noise_removed) / noise : 1.0; }
};

/// Background-activity filter (see the file comment). Not thread-safe; one per event stream.
class BackgroundActivityFilter {
 public:
  /// Throws std::invalid_argument for an invalid config or an empty / too large sensor
  /// (at most 4096 x 4096 pixels).
  BackgroundActivityFilter(const BackgroundActivityFilterConfig& config, SensorSize sensor);

  /// Filters `count` events in time order, appending the ones that pass to `passed` (which may
  /// not alias `events`); returns how many passed. All events are checked first: an event
  /// outside the sensor or earlier than its predecessor (also across calls) throws
  /// std::invalid_argument naming its index, and nothing of the call is processed (the state is
  /// unchanged). Call reset() when the stream restarts (e.g. a bag loops).
  std::size_t filter(const Event* events, std::size_t count, EventVector& passed);
  std::size_t filter(const EventVector& events, EventVector& passed) {
    return filter(events.data(), events.size(), passed);
  }
  /// Filters in place: `events` keeps the events that pass, in order. As filter() otherwise.
  std::size_t filterInPlace(EventVector& events);

  /// Per-event decision without validation: the caller guarantees that `e` lies inside the
  /// sensor and is not earlier than the previous event. Updates the maps; returns whether `e`
  /// passes.
  bool accept(const Event& e) {
    const std::size_t pixel = static_cast<std::size_t>(e.y + 1) * stride_ + (e.x + 1);
    const std::int64_t t = e.t_us;
    const std::int64_t w = config_.window_us;
    std::int64_t* map =
        last_time_.data() + (config_.polarity_match && e.polarity ? polarity_offset_ : 0);
    const std::int64_t* above = map + pixel - stride_ - 1;
    const std::int64_t* row = map + pixel - 1;
    const std::int64_t* below = map + pixel + stride_ - 1;
    const int support = (t - above[0] <= w) + (t - above[1] <= w) + (t - above[2] <= w) +
                        (t - row[0] <= w) + (t - row[2] <= w) + (t - below[0] <= w) +
                        (t - below[1] <= w) + (t - below[2] <= w);
    bool pass = support >= config_.min_support;
    if (config_.refractory_filter) {
      pass = pass && t - own_time_[pixel] >= config_.refractory_period_us;
      own_time_[pixel] = t;
    }
    map[pixel] = t;
    last_t_us_ = t;
    ++(pass ? passed_ : rejected_);
    return pass;
  }

  /// Forgets all activity (and the time order); the counters are kept.
  void reset();

  std::uint64_t passedCount() const { return passed_; }
  std::uint64_t rejectedCount() const { return rejected_; }
  const BackgroundActivityFilterConfig& config() const { return config_; }
  SensorSize sensor() const { return sensor_; }

 private:
  friend DenoisingScore scoreDenoising(const BackgroundActivityFilterConfig&, SensorSize,
                                       const EventVector&, const std::vector<std::uint8_t>&);
  void validate(const Event* events, std::size_t count) const;

  BackgroundActivityFilterConfig config_;
  SensorSize sensor_;
  std::size_t stride_ = 0;  // width + 2
  /// Per pixel (padded by one on each side) and polarity (OFF first, ON at polarity_offset_ if
  /// polarity_match): the time of its last event.
  std::vector<std::int64_t> last_time_;
  std::size_t polarity_offset_ = 0;
  /// Per pixel (same layout, either polarity): time of its last event (refractory filter only).
  std::vector<std::int64_t> own_time_;
  std::int64_t last_t_us_;
  std::uint64_t passed_ = 0;
  std::uint64_t rejected_ = 0;
};

/// Runs a fresh filter over `events` and scores its decisions against `is_noise` (one label per
/// event). Throws std::invalid_argument for mismatched sizes or invalid events (as filter()).
DenoisingScore scoreDenoising(const BackgroundActivityFilterConfig& config, SensorSize sensor,
                              const EventVector& events, const std::vector<std::uint8_t>& is_noise);

}  // namespace ebslam

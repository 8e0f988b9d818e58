#include "ebslam/events/event_denoiser.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace ebslam {
namespace {

// "Never": far enough in the past that t - kNever cannot overflow for any t >= kNever / 2 and
// exceeds every window.
constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min() / 4;

}  // namespace

void BackgroundActivityFilterConfig::validate() const {
  if (window_us <= 0) {
    throw std::invalid_argument("BackgroundActivityFilterConfig: window_us must be positive");
  }
  if (min_support < 1 || min_support > 8) {
    throw std::invalid_argument("BackgroundActivityFilterConfig: min_support must be in [1, 8]");
  }
  if (refractory_period_us < 0) {
    throw std::invalid_argument(
        "BackgroundActivityFilterConfig: refractory_period_us must be >= 0");
  }
}

BackgroundActivityFilter::BackgroundActivityFilter(const BackgroundActivityFilterConfig& config,
                                                   SensorSize sensor)
    : config_(config), sensor_(sensor), last_t_us_(kNever) {
  config_.validate();
  if (sensor.width == 0 || sensor.height == 0 || sensor.width > 4096 || sensor.height > 4096) {
    throw std::invalid_argument("BackgroundActivityFilter: sensor size " +
                                std::to_string(sensor.width) + " x " +
                                std::to_string(sensor.height) + " outside 1..4096");
  }
  stride_ = sensor.width + 2;
  reset();
}

void BackgroundActivityFilter::reset() {
  const std::size_t cells = stride_ * (sensor_.height + 2);
  polarity_offset_ = config_.polarity_match ? cells : 0;
  last_time_.assign(config_.polarity_match ? 2 * cells : cells, kNever);
  own_time_.assign(config_.refractory_filter ? cells : 0, kNever);
  last_t_us_ = kNever;
}

void BackgroundActivityFilter::validate(const Event* events, std::size_t count) const {
  std::int64_t last = last_t_us_;
  for (std::size_t i = 0; i < count; ++i) {
    const Event& e = events[i];
    if (!sensor_.contains(e)) {
      throw std::invalid_argument("BackgroundActivityFilter: event " + std::to_string(i) + " at (" +
                                  std::to_string(e.x) + ", " + std::to_string(e.y) +
                                  ") lies outside the " + std::to_string(sensor_.width) + " x " +
                                  std::to_string(sensor_.height) + " sensor");
    }
    if (e.t_us < last) {
      throw std::invalid_argument("BackgroundActivityFilter: event " + std::to_string(i) +
                                  " is earlier than its predecessor");
    }
    if (e.t_us < kNever / 2) {
      throw std::invalid_argument("BackgroundActivityFilter: event " + std::to_string(i) +
                                  " has a timestamp below the supported range");
    }
    last = e.t_us;
  }
}

std::size_t BackgroundActivityFilter::filter(const Event* events, std::size_t count,
                                             EventVector& passed) {
  if (count > 0 && events >= passed.data() && events < passed.data() + passed.size()) {
    throw std::invalid_argument("BackgroundActivityFilter: output aliases the input");
  }
  validate(events, count);
  std::size_t n = 0;
  for (std::size_t i = 0; i < count; ++i) {
    if (accept(events[i])) {
      passed.push_back(events[i]);
      ++n;
    }
  }
  return n;
}

std::size_t BackgroundActivityFilter::filterInPlace(EventVector& events) {
  validate(events.data(), events.size());
  std::size_t n = 0;
  for (std::size_t i = 0; i < events.size(); ++i) {
    if (accept(events[i])) events[n++] = events[i];
  }
  events.resize(n);
  return n;
}

DenoisingScore scoreDenoising(const BackgroundActivityFilterConfig& config, SensorSize sensor,
                              const EventVector& events,
                              const std::vector<std::uint8_t>& is_noise) {
  if (events.size() != is_noise.size()) {
    throw std::invalid_argument("scoreDenoising: " + std::to_string(events.size()) +
                                " events but " + std::to_string(is_noise.size()) + " labels");
  }
  BackgroundActivityFilter decide(config, sensor);
  decide.validate(events.data(), events.size());
  DenoisingScore score;
  for (std::size_t i = 0; i < events.size(); ++i) {
    const bool pass = decide.accept(events[i]);
    if (is_noise[i]) {
      ++score.noise;
      if (!pass) ++score.noise_removed;
    } else {
      ++score.signal;
      if (pass) ++score.signal_kept;
    }
  }
  return score;
}

}  // namespace ebslam

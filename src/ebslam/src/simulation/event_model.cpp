#include "ebslam/simulation/event_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ebslam {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

}  // namespace

void EventModelConfig::validate() const {
  require(std::isfinite(contrast_threshold_on) && contrast_threshold_on > 0.0,
          "EventModelConfig: contrast_threshold_on must be positive");
  require(std::isfinite(contrast_threshold_off) && contrast_threshold_off > 0.0,
          "EventModelConfig: contrast_threshold_off must be positive");
  require(std::isfinite(threshold_mismatch_sigma) && threshold_mismatch_sigma >= 0.0,
          "EventModelConfig: threshold_mismatch_sigma must be >= 0");
  require(std::isfinite(min_contrast_threshold) && min_contrast_threshold > 0.0,
          "EventModelConfig: min_contrast_threshold must be positive");
  require(std::isfinite(refractory_period_us) && refractory_period_us >= 0.0,
          "EventModelConfig: refractory_period_us must be >= 0");
  require(std::isfinite(noise_rate_hz_per_pixel) && noise_rate_hz_per_pixel >= 0.0,
          "EventModelConfig: noise_rate_hz_per_pixel must be >= 0");
  require(std::isfinite(noise_rate_log_sigma) && noise_rate_log_sigma >= 0.0 &&
              noise_rate_log_sigma <= 5.0,
          "EventModelConfig: noise_rate_log_sigma must be in [0, 5]");
  require(
      std::isfinite(hot_pixel_fraction) && hot_pixel_fraction >= 0.0 && hot_pixel_fraction <= 1.0,
      "EventModelConfig: hot_pixel_fraction must be in [0, 1]");
  require(std::isfinite(hot_pixel_rate_hz) && hot_pixel_rate_hz >= 0.0,
          "EventModelConfig: hot_pixel_rate_hz must be >= 0");
  require(std::isfinite(log_epsilon) && log_epsilon > 0.0,
          "EventModelConfig: log_epsilon must be positive");
}

EventGenerator::EventGenerator(const EventModelConfig& config, int width, int height)
    : config_(config) {
  config_.validate();
  require(width > 0 && height > 0 && width <= 65535 && height <= 65535,
          "EventGenerator: width and height must lie in [1, 65535]");
  width_ = width;
  pixel_count_ = static_cast<std::size_t>(width) * height;
  // Independent streams for the fixed pattern (thresholds, initial phase) and the noise, so
  // that changing the noise rate does not change the thresholds.
  pattern_rng_.seed(config_.seed);
  noise_rng_.seed(config_.seed ^ 0x9e3779b97f4a7c15ULL);
  std::normal_distribution<double> mismatch(0.0, 1.0);
  threshold_on_.resize(pixel_count_);
  threshold_off_.resize(pixel_count_);
  for (std::size_t i = 0; i < pixel_count_; ++i) {
    threshold_on_[i] = static_cast<float>(std::max(
        config_.min_contrast_threshold,
        config_.contrast_threshold_on + config_.threshold_mismatch_sigma * mismatch(pattern_rng_)));
    threshold_off_[i] =
        static_cast<float>(std::max(config_.min_contrast_threshold,
                                    config_.contrast_threshold_off +
                                        config_.threshold_mismatch_sigma * mismatch(pattern_rng_)));
  }
  // Background noise: one Poisson process over the sensor at the total rate, each event at a
  // pixel drawn with probability proportional to the pixel's rate. Equal rates (no spread, no
  // hot pixels) draw the pixel uniformly.
  noise_rate_total_ = config_.noise_rate_hz_per_pixel * static_cast<double>(pixel_count_);
  if (config_.noise_rate_log_sigma > 0.0 || config_.hot_pixel_fraction > 0.0) {
    std::mt19937_64 rate_rng(config_.seed ^ 0x5851f42d4c957f2dULL);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::normal_distribution<double> log_rate(
        -0.5 * config_.noise_rate_log_sigma * config_.noise_rate_log_sigma,
        config_.noise_rate_log_sigma);
    noise_rate_cumulative_.resize(pixel_count_);
    double sum = 0.0;
    for (std::size_t i = 0; i < pixel_count_; ++i) {
      const double spread = config_.noise_rate_log_sigma > 0.0 ? std::exp(log_rate(rate_rng)) : 1.0;
      const bool hot = uniform(rate_rng) < config_.hot_pixel_fraction;
      sum += hot ? config_.hot_pixel_rate_hz : config_.noise_rate_hz_per_pixel * spread;
      noise_rate_cumulative_[i] = sum;
    }
    noise_rate_total_ = sum;
  }
}

void EventGenerator::start(const std::vector<float>& intensity, double t_s) {
  require(intensity.size() == pixel_count_, "EventGenerator::start: image has the wrong size");
  require(std::isfinite(t_s), "EventGenerator::start: time must be finite");
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const float epsilon = static_cast<float>(config_.log_epsilon);
  log_previous_.resize(pixel_count_);
  reference_.resize(pixel_count_);
  last_event_s_.assign(pixel_count_, -kInfinity);
  for (std::size_t i = 0; i < pixel_count_; ++i) {
    log_previous_[i] = std::log(intensity[i] + epsilon);
    reference_[i] = log_previous_[i];
    if (config_.randomize_initial_reference) {
      // Reference uniformly inside (L - C_on, L + C_off): no pending crossing, random phase.
      reference_[i] += static_cast<float>(
          -threshold_on_[i] + uniform(pattern_rng_) * (threshold_on_[i] + threshold_off_[i]));
    }
  }
  if (noise_rate_total_ > 0.0) {
    std::exponential_distribution<double> noise_gap(noise_rate_total_);
    next_noise_s_ = t_s + noise_gap(noise_rng_);
  } else {
    next_noise_s_ = kInfinity;
  }
  t_previous_s_ = t_s;
  started_ = true;
}

std::size_t EventGenerator::step(const std::vector<float>& intensity, double t_s,
                                 EventVector& events, std::vector<std::uint8_t>* is_noise) {
  if (!started_) throw std::logic_error("EventGenerator::step called before start");
  require(intensity.size() == pixel_count_, "EventGenerator::step: image has the wrong size");
  require(std::isfinite(t_s) && t_s > t_previous_s_,
          "EventGenerator::step: time must be after the previous image");
  const std::size_t first = events.size();
  const double t0 = t_previous_s_;
  const double dt = t_s - t0;
  const double refractory_s = config_.refractory_period_us * 1e-6;
  const float epsilon = static_cast<float>(config_.log_epsilon);
  for (std::size_t i = 0; i < pixel_count_; ++i) {
    const float l0 = log_previous_[i];
    const float l1 = std::log(intensity[i] + epsilon);
    log_previous_[i] = l1;
    float ref = reference_[i];
    const float c_on = threshold_on_[i];
    const float c_off = threshold_off_[i];
    if (l1 - ref < c_on && ref - l1 < c_off) continue;
    const float change = l1 - l0;
    const bool on = l1 > ref;
    const float c = on ? c_on : c_off;
    const float direction = on ? 1.0f : -1.0f;
    // Each crossed level ref +- k c gives one event at the linearly interpolated time.
    while (on ? (l1 - ref >= c) : (ref - l1 >= c)) {
      ref += direction * c;
      double fraction = change != 0.0f ? static_cast<double>(ref - l0) / change : 1.0;
      fraction = std::clamp(fraction, 0.0, 1.0);
      const double t_event = t0 + fraction * dt;
      if (t_event - last_event_s_[i] >= refractory_s) {
        last_event_s_[i] = t_event;
        Event event;
        event.t_us = std::llround(t_event * 1e6);
        event.x = static_cast<std::uint16_t>(i % width_);
        event.y = static_cast<std::uint16_t>(i / width_);
        event.polarity = on;
        events.push_back(event);
      }
    }
    reference_[i] = ref;
  }
  const std::size_t signal = events.size() - first;
  if (std::isfinite(next_noise_s_)) {
    std::exponential_distribution<double> noise_gap(noise_rate_total_);
    std::uniform_int_distribution<std::size_t> noise_pixel(0, pixel_count_ - 1);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    while (next_noise_s_ < t_s) {
      std::size_t i = 0;
      if (noise_rate_cumulative_.empty()) {
        i = noise_pixel(noise_rng_);
      } else {
        const double u = uniform(noise_rng_) * noise_rate_total_;
        const auto it =
            std::upper_bound(noise_rate_cumulative_.begin(), noise_rate_cumulative_.end(), u);
        i = std::min<std::size_t>(pixel_count_ - 1,
                                  static_cast<std::size_t>(it - noise_rate_cumulative_.begin()));
      }
      Event event;
      event.t_us = std::llround(next_noise_s_ * 1e6);
      event.x = static_cast<std::uint16_t>(i % width_);
      event.y = static_cast<std::uint16_t>(i / width_);
      event.polarity = uniform(noise_rng_) < 0.5;
      events.push_back(event);
      next_noise_s_ += noise_gap(noise_rng_);
    }
  }
  auto earlier = [](const Event& a, const Event& b) {
    if (a.t_us != b.t_us) return a.t_us < b.t_us;
    if (a.y != b.y) return a.y < b.y;
    return a.x < b.x;
  };
  if (is_noise == nullptr) {
    std::sort(events.begin() + static_cast<std::ptrdiff_t>(first), events.end(), earlier);
  } else {
    // Events with their labels, sorted together; the order is the one std::sort gives the
    // events alone (same comparisons on the same sequence).
    struct LabelledEvent {
      Event event;
      std::uint8_t noise;
    };
    const std::size_t count = events.size() - first;
    std::vector<LabelledEvent> sorted(count);
    for (std::size_t k = 0; k < count; ++k) {
      sorted[k] = {events[first + k], static_cast<std::uint8_t>(k >= signal)};
    }
    std::sort(sorted.begin(), sorted.end(), [&](const LabelledEvent& a, const LabelledEvent& b) {
      return earlier(a.event, b.event);
    });
    for (std::size_t k = 0; k < count; ++k) {
      events[first + k] = sorted[k].event;
      is_noise->push_back(sorted[k].noise);
    }
  }
  t_previous_s_ = t_s;
  return signal;
}

}  // namespace ebslam

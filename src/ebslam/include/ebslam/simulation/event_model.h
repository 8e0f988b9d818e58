#pragma once

// Per-pixel event generation of a dynamic vision sensor (log-intensity change detector), shared
// by the ceiling simulator (simulator.h) and the D-eDVS room simulator (dedvs_simulator.h):
// contrast-threshold crossings with per-pixel mismatch, a refractory period and Poisson
// background noise; everything random is seeded. Details: docs/event_simulator.md#model

#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "ebslam/events/event.h"

namespace ebslam {

/// Parameters of the per-pixel event generation model.
struct EventModelConfig {
  /// Mean ON and OFF contrast threshold C in natural-log intensity units. Not given in the
  /// thesis; 0.15 (a 16 % brightness change) is a typical DVS128 / eDVS bias setting.
  double contrast_threshold_on = 0.15;
  double contrast_threshold_off = 0.15;
  /// Standard deviation of the per-pixel threshold mismatch [log units]; the DVS128 paper
  /// (Lichtsteiner et al. 2008) reports about 2.1 % contrast mismatch.
  double threshold_mismatch_sigma = 0.021;
  /// Lower bound of any pixel's threshold after mismatch [log units].
  double min_contrast_threshold = 0.01;
  /// Dead time after an event [us]; the eDVS' is about 100 us (thesis table 6.2). Crossings
  /// during it emit no event but still move the reference level.
  double refractory_period_us = 100.0;
  /// Background activity per pixel [Hz], the mean over the pixels; random pixel, polarity and
  /// time (Poisson process). Real DVS128-class sensors show 0.1-1 Hz and more (it rises with
  /// temperature and in dim light).
  double noise_rate_hz_per_pixel = 0.1;
  /// Spread of the background rate across pixels: std. dev. of ln(rate), log-normal with the
  /// mean kept (0 = one rate; measured DVS pixels: about 1, an order of magnitude).
  double noise_rate_log_sigma = 0.0;
  /// Fraction of hot pixels in [0, 1]: pixels (chosen at random) that fire noise at
  /// hot_pixel_rate_hz instead of their background rate.
  double hot_pixel_fraction = 0.0;
  double hot_pixel_rate_hz = 50.0;  ///< noise rate of a hot pixel [Hz]
  /// Added to the intensity before the logarithm (dark current); bounds the log contrast of
  /// black texels.
  double log_epsilon = 0.02;
  /// Start every pixel's reference level at a uniformly random phase inside its threshold band
  /// (as after an unknown history) instead of at its first intensity.
  bool randomize_initial_reference = true;
  /// Seeds threshold mismatch, initial references, noise and the per-pixel noise rates
  /// (separate streams: changing the noise settings leaves the fixed pattern unchanged).
  std::uint64_t seed = 1;

  /// Throws std::invalid_argument with the reason for out-of-range values.
  void validate() const;
};

/// The event model of a width x height sensor. Feed it intensity images (row-major, linear
/// intensity >= 0, one float per pixel) in time order: start() with the first, then step()
/// with each next one.
class EventGenerator {
 public:
  /// Draws the per-pixel thresholds. Throws std::invalid_argument for an invalid config or
  /// size.
  EventGenerator(const EventModelConfig& config, int width, int height);

  /// Sets the reference levels from the first image at time t_s [s]. Throws
  /// std::invalid_argument if the image has the wrong size.
  void start(const std::vector<float>& intensity, double t_s);

  /// Advances from the previous image to `intensity` at t_s (> previous time) and appends this
  /// interval's events, signal and noise, sorted by (time, row, column), to `events`. Event
  /// times are round(t * 1e6) microseconds. Returns the number of signal events appended (the
  /// rest are noise). Throws std::logic_error before start(), std::invalid_argument for a
  /// wrong size or a time not after the previous one. With `is_noise`, a flag per appended
  /// event (1 = background noise) is appended to it in the same order.
  std::size_t step(const std::vector<float>& intensity, double t_s, EventVector& events,
                   std::vector<std::uint8_t>* is_noise = nullptr);

  /// Time of the last image [s].
  double time() const { return t_previous_s_; }
  /// Log intensity log(I + epsilon) of the last image, per pixel.
  const std::vector<float>& logIntensity() const { return log_previous_; }

 private:
  EventModelConfig config_;
  int width_ = 0;
  std::size_t pixel_count_ = 0;
  std::mt19937_64 pattern_rng_;
  std::mt19937_64 noise_rng_;
  std::vector<float> threshold_on_;
  std::vector<float> threshold_off_;
  std::vector<float> log_previous_;
  std::vector<float> reference_;
  std::vector<double> last_event_s_;
  std::vector<double> noise_rate_cumulative_;  // empty: every pixel at the same rate
  double noise_rate_total_ = 0.0;
  double t_previous_s_ = 0.0;
  double next_noise_s_ = 0.0;
  bool started_ = false;
};

}  // namespace ebslam

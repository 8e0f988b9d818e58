#include "ebslam/calibration/dedvs_rgbd_led.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Dense>

namespace ebslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

std::string format(const char* pattern, double a, double b = 0.0, double c = 0.0) {
  char buffer[512];
  std::snprintf(buffer, sizeof(buffer), pattern, a, b, c);
  return buffer;
}

bool validDepth(float z) { return std::isfinite(z) && z > 0.0f; }

// Robust plane 1/z = a du + b dv + c over the valid depth pixels within `radius` of `pixel`
// in all frames (the plate rests): starting from the flat plane through the median, the pixels
// within `sigmas` robust standard deviations (1.4826 x median absolute residual) of the current
// plane are fitted by least squares, four times. Returns z at the pixel and the pixel count of
// the final fit, or nullopt with fewer than min_pixels.
std::optional<std::pair<double, int>> robustPlaneDepth(const std::vector<RgbdLedFrame>& frames,
                                                       const Eigen::Vector2d& pixel,
                                                       const RgbdLedConfig& config) {
  const double radius = config.depth_fit_radius_px;
  const int r = static_cast<int>(std::ceil(radius));
  const int cx = static_cast<int>(std::lround(pixel.x()));
  const int cy = static_cast<int>(std::lround(pixel.y()));
  std::vector<Eigen::Vector3d> rows;
  std::vector<double> values;
  for (const RgbdLedFrame& frame : frames) {
    const cv::Mat& depth = frame.depth_m;
    for (int row = std::max(0, cy - r); row <= std::min(depth.rows - 1, cy + r); ++row) {
      for (int col = std::max(0, cx - r); col <= std::min(depth.cols - 1, cx + r); ++col) {
        const Eigen::Vector2d offset = Eigen::Vector2d(col, row) - pixel;
        if (offset.norm() > radius) continue;
        const float z = depth.at<float>(row, col);
        if (!validDepth(z)) continue;
        rows.emplace_back(offset.x(), offset.y(), 1.0);
        values.push_back(1.0 / z);
      }
    }
  }
  if (static_cast<int>(rows.size()) < config.min_depth_pixels) return std::nullopt;
  Eigen::Vector3d solution = Eigen::Vector3d::Zero();
  {
    std::vector<double> sorted = values;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    solution.z() = sorted[sorted.size() / 2];
  }
  int count = 0;
  std::vector<double> residuals(rows.size());
  for (int pass = 0; pass < 4; ++pass) {
    for (std::size_t i = 0; i < rows.size(); ++i) {
      residuals[i] = std::abs(rows[i].dot(solution) - values[i]);
    }
    std::vector<double> sorted = residuals;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    // The floor keeps a noise-free (quantised, identical) depth from rejecting everything.
    const double threshold =
        config.depth_outlier_sigmas * std::max(1.4826 * sorted[sorted.size() / 2], 1e-9);
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    count = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (residuals[i] > threshold) continue;
      normal += rows[i] * rows[i].transpose();
      rhs += rows[i] * values[i];
      ++count;
    }
    if (count < config.min_depth_pixels) return std::nullopt;
    solution = normal.ldlt().solve(rhs);
    if (!solution.allFinite() || !(solution.z() > 0.0)) return std::nullopt;
  }
  return std::make_pair(1.0 / solution.z(), count);
}

}  // namespace

void RgbdLedConfig::validate() const {
  require(std::isfinite(led_frequency_hz) && led_frequency_hz > 0.0,
          "RgbdLedConfig: led_frequency_hz must be positive");
  require(std::isfinite(change_threshold) && change_threshold > 0.0 && max_changed_pixels >= 0 &&
              std::isfinite(led_exclusion_radius_px) && led_exclusion_radius_px >= 0.0,
          "RgbdLedConfig: change_threshold must be positive, max_changed_pixels and "
          "led_exclusion_radius_px >= 0");
  require(min_frames >= 3 && max_frames >= min_frames,
          "RgbdLedConfig: need 3 <= min_frames <= max_frames");
  require(max_alias_coherence > 0.0 && max_alias_coherence < 1.0,
          "RgbdLedConfig: max_alias_coherence must lie in (0, 1)");
  require(std::isfinite(min_amplitude) && min_amplitude > 0.0 && std::isfinite(min_snr) &&
              min_snr >= 1.0,
          "RgbdLedConfig: min_amplitude must be positive and min_snr >= 1");
  require(min_explained_variance >= 0.0 && min_explained_variance < 1.0,
          "RgbdLedConfig: min_explained_variance must lie in [0, 1)");
  require(std::isfinite(spot_radius_px) && spot_radius_px >= 1.0,
          "RgbdLedConfig: spot_radius_px must be >= 1");
  require(min_weight_fraction > 0.0 && min_weight_fraction < 1.0,
          "RgbdLedConfig: min_weight_fraction must lie in (0, 1)");
  require(max_second_peak_ratio > 0.0 && max_second_peak_ratio <= 1.0,
          "RgbdLedConfig: max_second_peak_ratio must lie in (0, 1]");
  require(border_margin_px >= 0, "RgbdLedConfig: border_margin_px must be >= 0");
  require(std::isfinite(depth_fit_radius_px) && depth_fit_radius_px >= 2.0,
          "RgbdLedConfig: depth_fit_radius_px must be >= 2");
  require(std::isfinite(depth_outlier_sigmas) && depth_outlier_sigmas > 0.0,
          "RgbdLedConfig: depth_outlier_sigmas must be positive");
  require(min_depth_pixels >= 3, "RgbdLedConfig: min_depth_pixels must be >= 3");
}

const char* toString(RgbdLedStatus status) {
  switch (status) {
    case RgbdLedStatus::kFound:
      return "found";
    case RgbdLedStatus::kTooFewFrames:
      return "rest too short";
    case RgbdLedStatus::kFrequencyAliased:
      return "LED frequency aliased by the frame rate";
    case RgbdLedStatus::kNoBlinkingPixel:
      return "no pixel blinks at the LED frequency";
    case RgbdLedStatus::kAmbiguous:
      return "several spots blink";
    case RgbdLedStatus::kAtBorder:
      return "LED at the image border";
    case RgbdLedStatus::kNoDepth:
      return "no depth around the LED";
  }
  return "unknown";
}

RgbdLedObservation findRgbdLed(const std::vector<RgbdLedFrame>& frames,
                               const RgbdLedConfig& config) {
  config.validate();
  require(!frames.empty(), "findRgbdLed: no frames");
  const int width = frames.front().grey.cols;
  const int height = frames.front().grey.rows;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const RgbdLedFrame& f = frames[k];
    require(f.grey.type() == CV_32FC1 && f.depth_m.type() == CV_32FC1 && f.grey.cols == width &&
                f.grey.rows == height && f.depth_m.cols == width && f.depth_m.rows == height &&
                width > 0 && height > 0,
            "findRgbdLed: frames must be non-empty CV_32FC1 grey and depth images of one size");
    require(std::isfinite(f.t_s) && (k == 0 || f.t_s > frames[k - 1].t_s),
            "findRgbdLed: frame stamps must be finite and increasing");
  }
  RgbdLedObservation result;
  result.t_begin_s = frames.front().t_s;
  result.t_end_s = frames.back().t_s;
  result.frames = static_cast<int>(frames.size());
  if (result.frames < config.min_frames) {
    result.status = RgbdLedStatus::kTooFewFrames;
    return result;
  }
  // The LED sampled at the frame times: phasors exp(-i w t_k), relative to the first frame
  // (stamps may be large).
  const double n = static_cast<double>(frames.size());
  const double omega = 2.0 * kPi * config.led_frequency_hz;
  std::vector<std::complex<double>> phasor(frames.size());
  std::complex<double> mean_phasor = 0.0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    phasor[k] = std::polar(1.0, -omega * (frames[k].t_s - frames.front().t_s));
    mean_phasor += phasor[k] / n;
  }
  if (std::abs(mean_phasor) > config.max_alias_coherence) {
    result.status = RgbdLedStatus::kFrequencyAliased;
    return result;
  }
  // Per pixel: P = (1/n) sum_k (I_k - mean) exp(-i w t_k); |P| is the blink amplitude.
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  std::vector<std::complex<double>> amplitude(pixels, 0.0);
  std::vector<double> mean(pixels, 0.0);
  for (const RgbdLedFrame& frame : frames) {
    for (int row = 0; row < height; ++row) {
      const float* grey = frame.grey.ptr<float>(row);
      for (int col = 0; col < width; ++col) {
        mean[static_cast<std::size_t>(row) * width + col] += grey[col] / n;
      }
    }
  }
  for (std::size_t k = 0; k < frames.size(); ++k) {
    for (int row = 0; row < height; ++row) {
      const float* grey = frames[k].grey.ptr<float>(row);
      for (int col = 0; col < width; ++col) {
        const std::size_t i = static_cast<std::size_t>(row) * width + col;
        amplitude[i] += (grey[col] - mean[i]) * phasor[k] / n;
      }
    }
  }
  std::vector<double> magnitude(pixels);
  std::size_t peak = 0;
  for (std::size_t i = 0; i < pixels; ++i) {
    magnitude[i] = std::abs(amplitude[i]);
    if (magnitude[i] > magnitude[peak]) peak = i;
  }
  {
    std::vector<double> sorted = magnitude;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    result.noise = sorted[sorted.size() / 2];
  }
  result.amplitude = magnitude[peak];
  Eigen::Vector2d centre(static_cast<double>(peak % width), static_cast<double>(peak / width));
  result.pixel = centre;
  const double detectable = std::max(config.min_amplitude, config.min_snr * result.noise);
  // Share of the peak pixel's variance a sinusoid at the LED frequency explains (1 for a
  // sinusoid sampled over whole periods; a square wave's fundamental carries 81 %): low for
  // a light blinking at another frequency that leaks into this one.
  double variance = 0.0;
  for (const RgbdLedFrame& frame : frames) {
    const double d =
        frame.grey.at<float>(static_cast<int>(peak / width), static_cast<int>(peak % width)) -
        mean[peak];
    variance += d * d / n;
  }
  const double explained =
      variance > 0.0 ? 2.0 * result.amplitude * result.amplitude / variance : 0.0;
  if (result.amplitude < detectable || explained < config.min_explained_variance) {
    result.status = RgbdLedStatus::kNoBlinkingPixel;
    return result;
  }
  // A second blinking spot away from the first.
  const double exclusion = config.spot_radius_px;
  for (std::size_t i = 0; i < pixels; ++i) {
    if (magnitude[i] <= std::max(detectable, config.max_second_peak_ratio * result.amplitude)) {
      continue;
    }
    const Eigen::Vector2d pixel(static_cast<double>(i % width), static_cast<double>(i / width));
    if ((pixel - centre).norm() > exclusion) {
      result.status = RgbdLedStatus::kAmbiguous;
      return result;
    }
  }
  // The spot: the 8-connected region of pixels around the peak whose in-phase amplitude (noise
  // of random phase averages out) reaches min_weight_fraction of the peak, within
  // spot_radius_px; its weighted centroid. A region, not a disc around the peak: a near LED
  // saturates a flat-topped spot whose brightest pixel may lie anywhere on the top.
  const std::complex<double> reference = amplitude[peak] / std::abs(amplitude[peak]);
  const double min_weight = config.min_weight_fraction * result.amplitude;
  const Eigen::Vector2d peak_pixel = centre;
  std::vector<std::uint8_t> visited(pixels, 0);
  std::vector<std::size_t> stack{peak};
  visited[peak] = 1;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  double total = 0.0;
  bool at_border = false;
  while (!stack.empty()) {
    const std::size_t i = stack.back();
    stack.pop_back();
    const int col = static_cast<int>(i % width), row = static_cast<int>(i / width);
    const double weight = (amplitude[i] * std::conj(reference)).real();
    sum += weight * Eigen::Vector2d(col, row);
    total += weight;
    const int m = config.border_margin_px;
    if (col < m || row < m || col >= width - m || row >= height - m) at_border = true;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int c = col + dx, r = row + dy;
        if (c < 0 || r < 0 || c >= width || r >= height) continue;
        const std::size_t j = static_cast<std::size_t>(r) * width + c;
        if (visited[j] != 0) continue;
        visited[j] = 1;
        if ((Eigen::Vector2d(c, r) - peak_pixel).norm() > config.spot_radius_px) continue;
        if ((amplitude[j] * std::conj(reference)).real() < min_weight) continue;
        stack.push_back(j);
      }
    }
  }
  centre = sum / total;  // total > 0: the peak itself has weight result.amplitude
  result.pixel = centre;
  if (at_border || !centre.allFinite()) {
    result.status = RgbdLedStatus::kAtBorder;
    return result;
  }
  const std::optional<std::pair<double, int>> depth = robustPlaneDepth(frames, centre, config);
  if (!depth) {
    result.status = RgbdLedStatus::kNoDepth;
    return result;
  }
  result.depth_m = depth->first;
  result.depth_pixels = depth->second;
  result.status = RgbdLedStatus::kFound;
  return result;
}

RgbdLedTracker::RgbdLedTracker(const RgbdLedConfig& config) : config_(config) {
  config_.validate();
}

int RgbdLedTracker::changedPixels(const cv::Mat& previous, const cv::Mat& current) const {
  cv::Mat difference;
  cv::absdiff(previous, current, difference);
  cv::Point largest;
  cv::minMaxLoc(difference, nullptr, nullptr, nullptr, &largest);
  const double r2 = config_.led_exclusion_radius_px * config_.led_exclusion_radius_px;
  int changed = 0;
  for (int row = 0; row < difference.rows; ++row) {
    const float* d = difference.ptr<float>(row);
    for (int col = 0; col < difference.cols; ++col) {
      if (d[col] <= config_.change_threshold) continue;
      const double dx = col - largest.x, dy = row - largest.y;
      if (dx * dx + dy * dy > r2) ++changed;
    }
  }
  return changed;
}

std::optional<RgbdLedObservation> RgbdLedTracker::close() {
  std::vector<RgbdLedFrame> segment;
  std::swap(segment, segment_);
  if (segment.size() < 2) return std::nullopt;
  return findRgbdLed(segment, config_);
}

std::optional<RgbdLedObservation> RgbdLedTracker::push(RgbdLedFrame frame) {
  require(frame.grey.type() == CV_32FC1 && frame.depth_m.type() == CV_32FC1 &&
              frame.grey.size() == frame.depth_m.size() && !frame.grey.empty(),
          "RgbdLedTracker: frames must be CV_32FC1 grey and depth images of one size");
  std::optional<RgbdLedObservation> closed;
  if (!last_grey_.empty()) {
    require(last_grey_.size() == frame.grey.size(),
            "RgbdLedTracker: the frame size changed during the recording");
    require(frame.t_s > last_t_s_, "RgbdLedTracker: frame stamps must increase");
    last_changed_pixels_ = changedPixels(last_grey_, frame.grey);
    if (last_changed_pixels_ > config_.max_changed_pixels ||
        static_cast<int>(segment_.size()) >= config_.max_frames) {
      closed = close();
    }
  }
  last_grey_ = frame.grey;
  last_t_s_ = frame.t_s;
  segment_.push_back(std::move(frame));
  return closed;
}

std::optional<RgbdLedObservation> RgbdLedTracker::finish() { return close(); }

void LedPairingConfig::validate() const {
  require(std::isfinite(depth_clock_offset_s),
          "LedPairingConfig: depth_clock_offset_s must be finite");
  require(min_window_periods >= 2 && max_window_periods <= 64 &&
              min_window_periods <= max_window_periods,
          "LedPairingConfig: need 2 <= min_window_periods <= max_window_periods <= 64");
}

LedPairing pairLedObservations(const std::vector<Event>& events,
                               const std::vector<RgbdLedObservation>& observations,
                               const LedExtractionConfig& extraction,
                               const LedPairingConfig& config) {
  config.validate();
  extraction.validate();
  LedPairing pairing;
  for (const RgbdLedObservation& o : observations) {
    ++pairing.segments;
    ++pairing.rgbd_status[static_cast<std::size_t>(o.status)];
    if (o.status != RgbdLedStatus::kFound) continue;
    // The still frames span the rest (the plate rests a little longer: conservative).
    const double span_periods = (o.t_end_s - o.t_begin_s) * extraction.led_frequency_hz;
    const int periods =
        std::min(config.max_window_periods, static_cast<int>(std::floor(span_periods)));
    if (periods < config.min_window_periods) {
      ++pairing.too_short_for_edvs;
      continue;
    }
    LedExtractionConfig window = extraction;
    window.window_periods = periods;
    const double t_s = 0.5 * (o.t_begin_s + o.t_end_s) - config.depth_clock_offset_s;
    const std::optional<LedObservation> led = extractLed(events, t_s, window);
    if (!led) {
      ++pairing.edvs_missing;
      continue;
    }
    LedCorrespondence c;
    c.depth_pixel = o.pixel;
    c.depth_m = o.depth_m;
    c.edvs_pixel = led->pixel;
    pairing.correspondences.push_back(c);
    pairing.times_s.push_back(t_s);
  }
  return pairing;
}

std::optional<double> estimateDepthClockOffset(const std::vector<Event>& events,
                                               const std::vector<double>& frame_t_s,
                                               const std::vector<double>& frame_motion,
                                               double max_offset_s, double step_s,
                                               double min_correlation) {
  require(frame_t_s.size() == frame_motion.size(),
          "estimateDepthClockOffset: one motion value per frame");
  require(std::isfinite(max_offset_s) && max_offset_s >= 0.0 && std::isfinite(step_s) &&
              step_s > 0.0 && max_offset_s / step_s <= 1e6,
          "estimateDepthClockOffset: need max_offset_s >= 0, step_s > 0");
  const std::size_t n = frame_t_s.size();
  if (n < 3 || events.empty()) return std::nullopt;
  // Events before t [us] (events sorted by time).
  const auto before = [&events](double t_s) {
    const double t_us = t_s * 1e6;
    return static_cast<double>(
        std::lower_bound(events.begin(), events.end(), t_us,
                         [](const Event& e, double t) { return static_cast<double>(e.t_us) < t; }) -
        events.begin());
  };
  const auto correlation = [&](double offset) {
    double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    const double m = static_cast<double>(n - 1);
    for (std::size_t k = 1; k < n; ++k) {
      const double x = frame_motion[k];
      // Events per second in the interval: frames may be dropped (longer intervals).
      const double y = (before(frame_t_s[k] - offset) - before(frame_t_s[k - 1] - offset)) /
                       (frame_t_s[k] - frame_t_s[k - 1]);
      sx += x;
      sy += y;
      sxx += x * x;
      syy += y * y;
      sxy += x * y;
    }
    const double vx = sxx - sx * sx / m, vy = syy - sy * sy / m;
    if (!(vx > 0.0) || !(vy > 0.0)) return 0.0;
    return (sxy - sx * sy / m) / std::sqrt(vx * vy);
  };
  double best = -2.0, best_offset = 0.0;
  const int steps = static_cast<int>(std::floor(max_offset_s / step_s));
  for (int i = -steps; i <= steps; ++i) {
    const double offset = i * step_s;
    const double c = correlation(offset);
    if (c > best) {
      best = c;
      best_offset = offset;
    }
  }
  if (best < min_correlation) return std::nullopt;
  return best_offset;
}

std::string diagnoseLedPairing(const LedPairing& pairing, std::size_t min_poses,
                               const RgbdLedConfig& config, double frame_rate_hz) {
  const std::size_t poses = pairing.correspondences.size();
  if (poses >= min_poses) return {};
  auto count = [&pairing](RgbdLedStatus s) {
    return pairing.rgbd_status[static_cast<std::size_t>(s)];
  };
  const std::size_t found = count(RgbdLedStatus::kFound);
  const double f = config.led_frequency_hz;
  std::string message = "only " + std::to_string(poses) + " usable LED poses, at least " +
                        std::to_string(min_poses) + " are needed. ";
  if (pairing.segments == 0) {
    return message +
           "No still moment was found in the colour frames: hold the plate still for at least " +
           format(
               "%.2f s (%.0f frames) at each pose, and fix the colour camera's exposure and "
               "white balance (automatic exposure changes the whole image).",
               config.min_frames / std::max(frame_rate_hz, 1e-9), config.min_frames);
  }
  if (found == 0) {
    if (count(RgbdLedStatus::kFrequencyAliased) > 0) {
      return message +
             format(
                 "The LED frequency %.1f Hz is (nearly) a multiple of the colour frame rate "
                 "(%.2f Hz), so every frame sees the LED in the same phase and it does not "
                 "blink in the frames: run the LED at another frequency (e.g. %.1f Hz) and "
                 "pass it with --led-frequency.",
                 f, frame_rate_hz, f + frame_rate_hz / 3.0);
    }
    if (count(RgbdLedStatus::kTooFewFrames) == pairing.segments) {
      return message + format(
                           "The plate never rested for %.0f frames: hold it still longer "
                           "(%.2f s) at each pose.",
                           config.min_frames, config.min_frames / std::max(frame_rate_hz, 1e-9));
    }
    if (count(RgbdLedStatus::kAmbiguous) > count(RgbdLedStatus::kNoBlinkingPixel)) {
      return message +
             "Several spots blink at the LED frequency in the colour frames: switch off or "
             "cover other flickering lights (lamps, screens) and keep reflections of the LED out "
             "of view.";
    }
    return message +
           format(
               "The LED was not found in the colour frames: no pixel blinks at %.1f Hz. "
               "Check that the LED runs at the frequency given (--led-frequency), that the "
               "colour camera sees it, and that the camera's exposure is fixed and short "
               "(below %.1f ms, half an LED period; a long exposure averages the blinking).",
               f, 500.0 / f);
  }
  if (pairing.edvs_missing > found / 2) {
    return message +
           format(
               "The LED blinks in the colour frames but %.0f of %.0f poses have no LED at "
               "%.1f Hz in the eDVS events: check that the eDVS sees the LED (lens, focus, "
               "bias settings), that the LED frequency is right (--led-frequency), and the "
               "depth camera's clock offset (--depth-clock-offset).",
               static_cast<double>(pairing.edvs_missing), static_cast<double>(found), f);
  }
  if (pairing.too_short_for_edvs > found / 2) {
    return message +
           "The plate rested too briefly for the eDVS LED window: hold it still "
           "longer at each pose.";
  }
  if (count(RgbdLedStatus::kNoDepth) > found) {
    message +=
        "Many poses had no depth around the LED: keep the plate within the depth "
        "camera's range and facing it. ";
  }
  if (count(RgbdLedStatus::kAtBorder) > found) {
    message += "Many poses had the LED at the image border: keep it inside the image. ";
  }
  return message + "Record more poses, spread over the whole eDVS image and the depth range.";
}

std::string adviseCalibration(const DedvsCalibrationResult& result) {
  switch (result.status) {
    case CalibrationStatus::kOk:
      return {};
    case CalibrationStatus::kNotConverged:
      return "the solver did not converge: record more poses spread over the whole eDVS image "
             "and depth range, and check the initial guess (the eDVS focal length and mount).";
    case CalibrationStatus::kTooFewInliers:
      return "fewer than half of the poses fit one calibration: the LED was confused with "
             "something else or the depth camera's clock offset is wrong (--depth-clock-offset); "
             "keep other blinking lights out of view and hold the plate still at each pose.";
    case CalibrationStatus::kHighError:
      return format(
          "the reprojection error (%.2f px) is too high: hold the plate still at each "
          "pose, check the LED frequency and the depth camera's clock offset.",
          result.rmse_px);
    case CalibrationStatus::kInvalidCamera:
      return "the fitted lens distortion is not invertible: record poses with the LED in the "
             "image corners too, so that the distortion is determined.";
  }
  return "unknown calibration status";
}

}  // namespace ebslam

#pragma once

// The calibration LED of the D-eDVS (thesis 8.2) in recorded RGB-D frames and its pairing with
// the LED in the eDVS events, for a calibration from recorded sensor data (no simulator truth).
// The plate with the LED rests at each pose for a moment: still segments of consecutive colour
// frames are found, the LED is the pixel whose brightness blinks at the known LED frequency
// across the segment's frames (sampled at the frame times, so aliasing is handled exactly), its
// depth comes from the registered depth image around it (a robust plane fit), and the eDVS LED
// (extractLed) is taken over the same rest on the event clock. Pixels: the registered
// colour/depth camera's, centres at integer coordinates. Times [s]. Details:
// docs/dedvs_core.md#calibration-from-recorded-frames

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "ebslam/calibration/dedvs_calibration.h"
#include "ebslam/events/event.h"

namespace ebslam {

/// One RGB-D frame of a calibration recording.
struct RgbdLedFrame {
  double t_s = 0.0;  ///< the camera's stamp [s]
  cv::Mat grey;      ///< CV_32FC1 brightness of the colour image (8-bit grey levels)
  cv::Mat depth_m;   ///< CV_32FC1 depth registered to the colour image [m]; 0 or NaN = none
};

struct RgbdLedConfig {
  double led_frequency_hz = 250.0;  ///< the LED's known square-wave frequency [Hz]
  /// Stillness: between consecutive frames, a pixel whose brightness changes by more than
  /// change_threshold grey levels has changed; the scene is still when at most
  /// max_changed_pixels changed outside a disc of led_exclusion_radius_px around the largest
  /// change (the blinking LED itself).
  double change_threshold = 12.0;
  int max_changed_pixels = 60;
  double led_exclusion_radius_px = 25.0;
  /// Still frames needed for an observation (the blink is sampled once per frame); a longer
  /// rest is split into observations of at most max_frames.
  int min_frames = 5;
  int max_frames = 30;
  /// |mean over the frames of exp(-2 pi i f t_k)| above this: the frames see the LED at
  /// (nearly) the same phase, its blinking is invisible (LED frequency near a multiple of the
  /// frame rate).
  double max_alias_coherence = 0.7;
  /// The LED pixel's blink amplitude (fundamental, grey levels) must reach min_amplitude and
  /// min_snr times the median amplitude of the image.
  double min_amplitude = 4.0;
  double min_snr = 10.0;
  /// The share of the LED pixel's brightness variance across the frames that a sinusoid at
  /// the LED frequency explains must reach this (a light blinking at another frequency leaks
  /// into the LED frequency's amplitude over few frames, with a low share).
  double min_explained_variance = 0.5;
  /// Spot: the connected pixels around the strongest whose in-phase amplitude reaches
  /// min_weight_fraction of the peak, within spot_radius_px of it; weighted centroid. The
  /// radius must exceed the LED's spot (a saturated spot is flat-topped: its strongest pixel
  /// lies anywhere on the top).
  double spot_radius_px = 25.0;
  double min_weight_fraction = 0.2;
  /// Another detectable blinking pixel farther than spot_radius_px from the LED with more
  /// than this fraction of its amplitude makes the observation ambiguous (a second light).
  double max_second_peak_ratio = 0.35;
  int border_margin_px = 2;  ///< spot pixels this close to the border: no observation [px]
  /// Depth: plane 1/z = a du + b dv + c fitted to the valid depth pixels within this radius of
  /// the LED in all frames of the segment, refitted without residuals beyond
  /// depth_outlier_sigmas robust standard deviations; at least min_depth_pixels must remain.
  double depth_fit_radius_px = 6.0;
  double depth_outlier_sigmas = 3.0;
  int min_depth_pixels = 20;

  /// Throws std::invalid_argument for out-of-range values.
  void validate() const;
};

enum class RgbdLedStatus : std::uint8_t {
  kFound = 0,
  kTooFewFrames,      ///< the rest was shorter than min_frames frames
  kFrequencyAliased,  ///< the frame times sample the LED at one phase (see max_alias_coherence)
  kNoBlinkingPixel,   ///< nothing blinks at the LED frequency
  kAmbiguous,         ///< more than one spot blinks at the LED frequency
  kAtBorder,          ///< the LED's spot touches the image border
  kNoDepth,           ///< too few valid depth pixels around the LED
};
constexpr std::size_t kRgbdLedStatusCount = 7;
const char* toString(RgbdLedStatus status);

/// The LED in one still segment of frames.
struct RgbdLedObservation {
  RgbdLedStatus status = RgbdLedStatus::kNoBlinkingPixel;
  double t_begin_s = 0.0;  ///< first and last frame's stamp [s]
  double t_end_s = 0.0;
  int frames = 0;
  Eigen::Vector2d pixel{0.0, 0.0};  ///< [px] (kFound, kAtBorder, kNoDepth)
  double depth_m = 0.0;             ///< z of the LED [m] (kFound)
  double amplitude = 0.0;           ///< blink amplitude at the peak [grey levels]
  double noise = 0.0;               ///< median amplitude of the image [grey levels]
  int depth_pixels = 0;             ///< depth pixels of the final plane fit
};

/// The LED in `frames`, one still segment (same size, types as RgbdLedFrame, times increasing).
/// Throws std::invalid_argument for an invalid config, empty or mismatched images.
RgbdLedObservation findRgbdLed(const std::vector<RgbdLedFrame>& frames,
                               const RgbdLedConfig& config = {});

/// Splits a stream of frames into still segments and finds the LED in each (findRgbdLed).
class RgbdLedTracker {
 public:
  /// Throws std::invalid_argument for an invalid config.
  explicit RgbdLedTracker(const RgbdLedConfig& config = {});
  /// Adds the next frame (stamps increasing). Returns the observation of the still segment
  /// this frame closed (moving again, or max_frames reached), if it had at least two frames.
  /// Throws std::invalid_argument for a frame of another size or type, or a stamp not after
  /// the previous one.
  std::optional<RgbdLedObservation> push(RgbdLedFrame frame);
  /// Closes the last segment.
  std::optional<RgbdLedObservation> finish();
  /// Pixels that changed between the last two frames pushed (outside the LED disc; the
  /// plate's motion), -1 before the second frame.
  int lastChangedPixels() const { return last_changed_pixels_; }

 private:
  int changedPixels(const cv::Mat& previous, const cv::Mat& current) const;
  std::optional<RgbdLedObservation> close();

  RgbdLedConfig config_;
  std::vector<RgbdLedFrame> segment_;
  cv::Mat last_grey_;
  double last_t_s_ = 0.0;
  int last_changed_pixels_ = -1;
};

// ---------------------------------------------------------------------------------------------
// Pairing with the eDVS and the user-facing diagnosis.

struct LedPairingConfig {
  /// The depth camera's clock offset: event time = stamp - depth_clock_offset_s [s] (as in
  /// DedvsSensors).
  double depth_clock_offset_s = 0.0;
  /// The eDVS LED is extracted over the rest: a window of the segment's duration (in LED
  /// periods, clamped to [min_window_periods, max_window_periods]) centred on it; shorter rests
  /// are not used.
  int min_window_periods = 8;
  int max_window_periods = 64;

  /// Throws std::invalid_argument for out-of-range values.
  void validate() const;
};

struct LedPairing {
  std::vector<LedCorrespondence> correspondences;  ///< one per usable pose
  std::vector<double> times_s;                     ///< event-clock time of each correspondence [s]
  std::size_t segments = 0;                        ///< still segments seen
  std::array<std::size_t, kRgbdLedStatusCount> rgbd_status{};  ///< segments per status
  std::size_t too_short_for_edvs = 0;  ///< LED found in RGB-D, rest too short for the window
  std::size_t edvs_missing = 0;        ///< LED found in RGB-D, not in the events
};

/// Pairs the RGB-D observations with the LED in `events` (sorted by time, t_us on the event
/// clock) over the same rest. `extraction.window_periods` is set per observation. Throws
/// std::invalid_argument for an invalid config.
LedPairing pairLedObservations(const std::vector<Event>& events,
                               const std::vector<RgbdLedObservation>& observations,
                               const LedExtractionConfig& extraction,
                               const LedPairingConfig& config = {});

/// Measures the depth camera's clock offset (event time = frame stamp - offset) from the
/// plate's motion: frame_motion[k] (k >= 1) is how much the colour image changed between
/// frames k-1 and k (RgbdLedTracker::lastChangedPixels), the eDVS fires while the plate moves;
/// the offset in [-max_offset_s, max_offset_s] (steps of step_s) that maximises the correlation
/// of frame_motion with the event count in [t_{k-1}, t_k] - offset. `events` sorted by time,
/// frame_t_s increasing [s]. std::nullopt when the correlation stays below min_correlation
/// (no motion, or the sensors did not see the same thing). Throws std::invalid_argument for
/// mismatched sizes or non-positive steps.
std::optional<double> estimateDepthClockOffset(const std::vector<Event>& events,
                                               const std::vector<double>& frame_t_s,
                                               const std::vector<double>& frame_motion,
                                               double max_offset_s = 0.1, double step_s = 0.0005,
                                               double min_correlation = 0.5);

/// What keeps `pairing` from a calibration, in words a user can act on (empty when it has
/// at least `min_poses` poses). frame_rate_hz: the recording's colour frame rate [Hz].
std::string diagnoseLedPairing(const LedPairing& pairing, std::size_t min_poses,
                               const RgbdLedConfig& config, double frame_rate_hz);

/// What a calibration result's status means for the user and what to do about it (empty for
/// kOk).
std::string adviseCalibration(const DedvsCalibrationResult& result);

}  // namespace ebslam

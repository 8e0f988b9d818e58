#pragma once

// Event-based SLAM in 2D (thesis 7.2-7.3, alg. 8): EB-PF localisation against a ceiling map built
// from the same events. Dense grids on the ceiling plane: occurrence map O (eq. 7.6), normalisation
// map Z (eq. 7.7: path length on the sensor [pixels]) and map M = O / (Z + Z0) (eq. 7.5; a prior
// Z0 > 0 instead of alg. 8's M = 0 where Z = 0). G0 is fixed or measured by G0Tracker, never
// estimated from M (7.2.4). Details: docs/ebslam_core.md#eb-slam-2d

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "ebslam/events/event.h"
#include "ebslam/slam/ceiling_camera.h"
#include "ebslam/slam/event_filter.h"
#include "ebslam/slam/particle_set2d.h"

namespace ebslam {

/// Which poses splat an event into the occurrence map.
enum class OccurrenceSplat {
  kExpectedPose,  ///< one splat at the expected pose p_* (alg. 8 with p_*; fast)
  kAllParticles,  ///< one splat per particle weighted by its normalised score (eq. 7.6)
};

struct Ebslam2dConfig {
  /// Localisation: N = 10 (table 7.1 uses 5..75), G0 = 30 against the growing map (EB-PF: 60).
  /// Why: docs/ebslam_core.md#eb-slam-2d
  EventFilterConfig filter = [] {
    EventFilterConfig f;
    f.num_particles = 10;
    f.g0 = 30.0;
    return f;
  }();
  /// Map cell edge length in units of W_trig (7.2.4: "in the order of W_trig").
  double cell_size_wtrig = 1.0;
  /// Side length of the square map, centred on the start pose [m].
  double map_size_m = 24.0;
  /// sigma of the occurrence splat in units of W_trig (7.2.3: a multiple of W_trig); the kernel
  /// is cut at 3 sigma.
  double splat_sigma_wtrig = 0.5;
  OccurrenceSplat splat = OccurrenceSplat::kExpectedPose;
  /// Z is updated once the expected pose has moved the image by this much [pixels] (largest
  /// pixel displacement over the sensor; eq. 7.7).
  double normalisation_step_px = 1.0;
  /// Z0: prior number of possible observations per cell [pixels of path], see the file comment.
  double normalisation_prior_px = 1.0;
  /// Scale the per-event diffusion by the estimated signal fraction of the event rate (robust
  /// start under background activity; false = the thesis).
  /// docs/ebslam_core.md#noise-aware-diffusion
  bool noise_aware_diffusion = false;

  /// Tuning of the noise-aware diffusion, chosen on one simulated run (see the link above).
  struct Experimental {
    double rate_window_s = 0.02;  ///< window of the event rate [s]
    /// Gains of the background-rate estimate per window: towards a lower rate, and towards a
    /// higher rate below noise_floor_band times it.
    double noise_floor_gain_down = 0.3;
    double noise_floor_gain_up = 0.05;
    double noise_floor_band = 1.25;
  };
  Experimental experimental;

  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

class EventSlam2d {
 public:
  /// The map frame is the start pose's frame shifted by `start` (default: origin).
  /// Throws std::invalid_argument for an invalid config.
  EventSlam2d(const Ebslam2dConfig& config, const CeilingCamera& camera, const Pose2& start = {});

  /// Processes events in order (batches of B; validated as in EventParticleFilter::process:
  /// events outside the sensor or earlier than their predecessor throw std::invalid_argument and
  /// nothing of the call is processed; an empty span is a no-op).
  void process(const Event* events, std::size_t count);
  void process(const EventVector& events) { process(events.data(), events.size()); }
  /// `count` events of the stream that were left out before process() (a rate cap's thinning,
  /// EventRateLimiter): noise_aware_diffusion measures the stream's event rate, which they are
  /// part of. Counted into the current rate window (none before the first process()).
  void countUnprocessed(std::uint64_t count) {
    if (rate_window_started_) rate_window_events_ += count;
  }

  /// Expected pose p_* (score-weighted mean of the particles) or the best particle
  /// (config.filter.estimate).
  Pose2 estimate() const;
  const ParticleSet2D& particles() const { return particles_; }
  const GridMap2f& occurrence() const { return occurrence_; }
  const GridMap2f& normalisation() const { return normalisation_; }
  const GridMap2f& map() const { return map_; }
  std::uint64_t processedEvents() const { return processed_; }
  std::uint64_t normalisationUpdates() const { return normalisation_updates_; }
  double alpha() const { return schedule_.alpha; }
  const Ebslam2dConfig& config() const { return config_; }
  /// Changes the localisation's runtime knobs without losing the map; as
  /// EventParticleFilter::setFilterConfig.
  void setFilterConfig(const EventFilterConfig& filter);
  double g0() const { return schedule_.g0; }

 private:
  void setG0(double g0);
  /// c, s: cos and sin of pose.theta.
  void splat(const Pose2& pose, double c, double s, std::uint32_t pixel, float weight);
  void updateNormalisation(const Pose2& from, const Pose2& to);
  /// updateNormalisation without lens distortion over rows r0..r1 and world x in [x_min, x_max].
  void updateNormalisationPinhole(const Pose2& from, const Pose2& to, int r0, int r1, double x_min,
                                  double x_max);

  Ebslam2dConfig config_;
  CeilingCamera camera_;
  ParticleSet2D particles_;
  GridMap2f occurrence_;
  GridMap2f normalisation_;
  GridMap2f map_;
  GridMap2f inverse_normalisation_;  // 1 / (Z + Z0), so that a splat needs no division
  std::vector<float> kernel_;        // (2 r + 1)^2 Gaussian weights summing to 1
  int kernel_radius_ = 0;
  float z0_ = 1.0f;
  G0Schedule schedule_;
  G0Tracker g0_tracker_;
  /// A pose with its heading as a unit vector, so that the per-batch work needs no trigonometry.
  struct HeadingVectorPose {
    double x = 0.0, y = 0.0, c = 1.0, s = 0.0;
    static HeadingVectorPose from(const Pose2& p) {
      return {p.x, p.y, std::cos(p.theta), std::sin(p.theta)};
    }
    Pose2 pose() const { return {x, y, std::atan2(s, c)}; }
  };
  /// Largest image motion [pixels] between two poses (translation plus rotation at the sensor
  /// corner), with |sin dtheta| for |dtheta| (equal to within 2e-5 relative below 0.01 rad; a
  /// turn beyond 90 degrees counts as pi).
  double imageMotionPx(const HeadingVectorPose& a, const HeadingVectorPose& b) const;
  HeadingVectorPose expected_;
  HeadingVectorPose last_normalised_;
  std::uint64_t processed_ = 0;
  std::uint64_t normalisation_updates_ = 0;
  int since_resample_ = 0;
  std::int64_t last_t_us_;
  // Noise-aware diffusion: the current rate window and the background rate estimate.
  void updateSignalFraction(int events, std::int64_t t_us);
  std::int64_t rate_window_start_us_ = 0;
  bool rate_window_started_ = false;
  std::uint64_t rate_window_events_ = 0;
  double noise_floor_hz_ = 0.0;  // events/s over the sensor; 0 = not yet measured

 public:
  /// Estimated background event rate [events/s over the sensor] (noise_aware_diffusion).
  double backgroundRateHz() const { return noise_floor_hz_; }
  /// Signal fraction in use (1 unless noise_aware_diffusion).
  double signalFraction() const { return schedule_.signal_fraction; }
};

/// 8-bit image of a map for display: values scaled so that the given quantile of the non-zero
/// cells maps to full scale; `dark_is_high` draws high values dark (thesis fig. 7.3/7.6).
/// Row r of the image is grid row r (world y grows downwards in the image).
cv::Mat mapToImage(const GridMap2f& map, double quantile = 0.99, bool dark_is_high = true);

}  // namespace ebslam

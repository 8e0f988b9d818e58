#pragma once

// The event filter shared by EB-PF (ebpf.h, thesis 6.4) and EB-SLAM-2D's localisation (ebslam2d.h,
// alg. 8): its parameters, what follows from G0 (decay, diffusion), the online G0 estimate and the
// batched localisation pass of alg. 7. Notes: docs/ebslam_core.md#event-filter

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "ebslam/events/event.h"
#include "ebslam/slam/ceiling_camera.h"
#include "ebslam/slam/exponential_decay.h"
#include "ebslam/slam/particle_set2d.h"

namespace ebslam {

/// Which pose the filter reports.
enum class PoseEstimateMode {
  kWeightedMean,  ///< score-weighted mean of all particles (p_* of alg. 8)
  kBestParticle,  ///< the particle with the highest score (alg. 7)
};

/// Parameters shared by EB-PF and EB-SLAM-2D's localisation step.
struct EventFilterConfig {
  int num_particles = 50;    ///< N (6.5.3: 50)
  int batch_size = 3;        ///< B in [1, 64]: events scored together (6.5.3: 3), eq. 6.30/6.39
  int resample_every = 100;  ///< K: events between resamplings (6.5.3: 100)
  double beta = 0.95;        ///< relative influence of the last G0 events on a score (eq. 6.27)
  /// G0: effective feature count; sets alpha (eq. 6.27) and the diffusion (eq. 6.9/6.10). 60, not
  /// 6.3.2's 250: docs/ebslam_core.md#eb-pf-choice-of-g0
  double g0 = 60.0;
  PoseEstimateMode estimate = PoseEstimateMode::kWeightedMean;
  double initial_spread_m = 0.0;    ///< std. dev. of the initial particle positions [m]
  double initial_spread_rad = 0.0;  ///< std. dev. of the initial headings [rad]
  /// Event latency compensation [s]: the reported pose is extrapolated by this time (0 = the
  /// thesis). Why: docs/ebslam_core.md#latency-compensation
  double latency_compensation_s = 0.0;
  std::uint64_t seed = 1;  ///< seeds the particle noise and resampling

  /// Ablation knobs of the results pages (docs/results/events2d.md); the defaults are the thesis'
  /// model. Notes: docs/ebslam_core.md#event-filter
  struct Experimental {
    double diffusion_scale = 1.0;  ///< factor on the diffusion std. devs (1 = eq. 6.38)
    /// Resampled children get the mean score (true) instead of their parent's (false).
    bool reset_scores_on_resample = false;
    /// Re-estimate G0 online (G0Tracker; 7.2.4 asks for G0 from the data); `g0` starts it.
    bool adapt_g0 = false;
    double adapt_g0_divisor = 50.0;  ///< adapted G0 = measured events per pixel / this
    double adapt_g0_min = 5.0;       ///< clamp of the adapted G0
    double adapt_g0_max = 1000.0;
    double velocity_window_s = 0.1;  ///< baseline of the latency compensation's velocity [s]
  };
  Experimental experimental;

  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

/// Checks a span of events against the sensor and the previous timestamp (last_t_us, updated
/// only when every event passes).
/// Throws std::invalid_argument naming the index of the first event outside the sensor or
/// earlier than its predecessor.
void validateEvents(const Event* events, std::size_t count, int width, int height,
                    std::int64_t& last_t_us);

/// Per-event diffusion standard deviations of eq. 6.9/6.10 [m, rad] for a filter config.
struct Diffusion {
  double sigma_xy_m = 0.0;
  double sigma_theta_rad = 0.0;
};
Diffusion perEventDiffusion(const EventFilterConfig& config, const CeilingCamera& camera,
                            double g0);

/// Everything that follows from G0 in an event filter: the decay alpha (eq. 6.27), the per-event
/// diffusion (eq. 6.38) and the score decay of a batch of b = 1..B events (eq. 6.39), index b - 1.
struct G0Schedule {
  double g0 = 0.0;
  double alpha = 0.0;
  Diffusion diffusion;
  std::vector<BatchDecay> batch_decay;
  /// Expected fraction of the events that come from motion (not background activity) in
  /// [0, 1]: the per-event diffusion variance is scaled by it (1 = eq. 6.38).
  double signal_fraction = 1.0;
};
G0Schedule makeG0Schedule(const EventFilterConfig& config, const CeilingCamera& camera, double g0);

/// Online G0 from the event stream and the pose estimate: events per pixel of net image motion
/// (eq. 6.6 and 6.8 inverted), exponentially smoothed, / adapt_g0_divisor, clamped.
/// Details: docs/ebslam_core.md#event-filter
class G0Tracker {
 public:
  G0Tracker() = default;
  G0Tracker(const EventFilterConfig& config, const CeilingCamera& camera, const Pose2& start);
  /// Adds `events` processed events and the current estimate; returns a new G0 when a window
  /// completes, otherwise 0.
  double update(std::uint64_t events, const Pose2& estimate);
  double eventsPerPixel() const { return smoothed_; }

 private:
  double w_trig_ = 0.03;
  double rotation_radius_px_ = 49.0;
  double divisor_ = 50.0, min_ = 5.0, max_ = 1000.0;
  Pose2 window_start_;
  std::uint64_t window_events_ = 0;
  double smoothed_ = 0.0;
};

/// A filter's switch to a new EventFilterConfig at run time (EB-PF and EB-SLAM-2D alike): returns
/// the G0 to continue with (the adapted G0 of `schedule` while G0 adaptation stays on, otherwise
/// the new config's), and re-draws the particles around `current` with the new spreads and seed
/// when the particle count changed (otherwise they are kept). The caller validates `next`.
double switchFilterConfig(const EventFilterConfig& previous, const EventFilterConfig& next,
                          const G0Schedule& schedule, const Pose2& current,
                          ParticleSet2D& particles);

/// The localisation pass of alg. 7 (alg. 8's "update particles"): scores the particles against
/// `map` for `events` in batches of at most config.batch_size, each batch diffused with b times
/// the per-event variance (eq. 6.39) times schedule.signal_fraction, and resamples every
/// config.resample_every events. After each batch, after_batch(pixel_index, b, resampled,
/// batch_end) runs with the batch's pixel indices (row-major into the camera image), its size,
/// whether it resampled, and the index in `events` one past the batch. `map` and `schedule` are
/// read afresh for every batch, so the callback may change them. The events must be validated.
template <typename AfterBatch>
void localiseInBatches(const Event* events, std::size_t count, const CeilingCamera& camera,
                       const EventFilterConfig& config, const G0Schedule& schedule,
                       const GridMap2f& map, ParticleSet2D& particles, std::uint64_t& processed,
                       int& since_resample, AfterBatch&& after_batch) {
  const float* ox = camera.offsetX().data();
  const float* oy = camera.offsetY().data();
  std::uint32_t index[64];  // batch_size <= 64 (validated with the config)
  std::size_t i = 0;
  while (i < count) {
    const int b = static_cast<int>(std::min<std::size_t>(config.batch_size, count - i));
    for (int j = 0; j < b; ++j) {
      const Event& e = events[i + j];
      index[j] = static_cast<std::uint32_t>(e.y) * camera.width() + e.x;
    }
    // Diffusion variance of b events, each carrying motion with probability signal_fraction.
    const double root_b = std::sqrt(static_cast<double>(b) * schedule.signal_fraction);
    particles.step(index, b, ox, oy, map, schedule.diffusion.sigma_xy_m * root_b,
                   schedule.diffusion.sigma_theta_rad * root_b, schedule.batch_decay[b - 1]);
    i += b;
    processed += b;
    since_resample += b;
    const bool resampled = since_resample >= config.resample_every;
    if (resampled) {
      particles.resampleSystematic(config.experimental.reset_scores_on_resample);
      since_resample -= config.resample_every;
    }
    after_batch(static_cast<const std::uint32_t*>(index), b, resampled, i);
  }
}

}  // namespace ebslam

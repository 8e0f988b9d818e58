#pragma once

// Event-based Particle Filter (thesis 6.4, alg. 7) for robot self-localisation under a ceiling
// with a known map (6.5): SE(2) particles, per-event diffusion motion model (eq. 6.38/6.39 with
// Delta_x, Delta_theta of eq. 6.9/6.10), sensor model from a cached distance transform of the
// ceiling's edge map (eq. 6.36/6.37), exponential-decay scores (eq. 6.29/6.30), resampling
// every K events.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "ebslam/ceiling_camera.h"
#include "ebslam/event.h"
#include "ebslam/particles2d.h"

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
  /// G0: effective number of feature points seen; sets the decay alpha (eq. 6.27) and the
  /// per-event diffusion Delta_x = D / (f G0), Delta_theta = 3 / (S G0) (eq. 6.9/6.10). 60, not
  /// the thesis' example 250 (6.3.2), which loses the simulated runs; a property of scene and
  /// sensor, set per setup (or adapt_g0). Why: docs/ebslam_core.md#eb-pf-choice-of-g0
  double g0 = 60.0;
  /// Extra factor on the diffusion standard deviations (1 = eq. 6.38 exactly).
  double diffusion_scale = 1.0;
  double initial_spread_m = 0.0;    ///< std. dev. of the initial particle positions [m]
  double initial_spread_rad = 0.0;  ///< std. dev. of the initial headings [rad]
  /// Children keep their parent's score on resampling (false) or all scores are reset to the
  /// mean (true).
  bool reset_scores_on_resample = false;
  /// Re-estimate G0 online (7.2.4 asks for G0 from the data; see G0Tracker) instead of keeping
  /// `g0` fixed; `g0` is then the starting value.
  bool adapt_g0 = false;
  /// Adaptive G0: the measured events per pixel of image motion divided by this factor. The
  /// diffusion has to cover the motion between resamplings, so the effective G0 is well below
  /// the raw event density; 50 was found on the synthetic test scene (test/synthetic_ceiling.h,
  /// about 2000 events per pixel, best fixed G0 50-100).
  double adapt_g0_divisor = 50.0;
  double adapt_g0_min = 5.0;  ///< clamp of the adapted G0
  double adapt_g0_max = 1000.0;
  PoseEstimateMode estimate = PoseEstimateMode::kWeightedMean;
  /// Event latency compensation [s]: estimate() reports the filtered pose extrapolated by this
  /// time with the velocity of the raw estimate (VelocityEstimator over `velocity_window_s`).
  /// A DVS pixel fires only after its log intensity has changed by a whole contrast threshold
  /// since its last event, i.e. on average half a threshold after a moving edge reached the
  /// pixel centre; the events therefore show the edges slightly behind their true position and
  /// the filter localises the pose of a moment earlier. 0 (the thesis) reports the raw pose.
  double latency_compensation_s = 0.0;
  double velocity_window_s = 0.1;  ///< baseline of the velocity estimate [s]
  std::uint64_t seed = 1;          ///< seeds the particle noise and resampling

  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

/// EB-PF parameters: the filter plus the sensor model.
struct EbpfConfig {
  EventFilterConfig filter;
  /// gamma: sensor-model standard deviation in units of W_trig (eq. 6.37: 0.5, events are
  /// accurate to half a pixel).
  double gamma = 0.5;
  void validate() const;
};

/// Cached sensor model of eq. 6.37 on a grid: value exp(-0.5 (d / sigma)^2) with d the distance
/// [m] from the cell centre to the nearest edge pixel (cv::distanceTransform, exact Euclidean).
/// edges: CV_8UC1, non-zero on edges. Pixel (col, row) of the edge image has its centre at world
/// (origin_centre_m.x() + col res, origin_centre_m.y() + row res), as CeilingMap in
/// simulator_scenes.h. Throws std::invalid_argument for an empty or wrongly typed image, an image
/// without edges, or non-positive resolution / sigma.
GridMap2f makeEdgeLikelihoodMap(const cv::Mat& edges, double metres_per_pixel,
                                const Eigen::Vector2d& origin_centre_m, double sigma_m);

/// Checks a span of events against the sensor and the previous timestamp (last_t_us, updated).
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
/// diffusion (eq. 6.38) and the score decay of a batch of b = 1..B events (eq. 6.39), indexed b
/// - 1.
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

/// Online G0 from the event stream and the pose estimate: events per pixel of image motion
/// (eq. 6.6 and 6.8 inverted, E = G0 x / W_trig + 0.38 S G0 theta), measured over windows of at
/// least one pixel of net motion of the estimate (net, so that estimate jitter does not count as
/// motion), exponentially smoothed; the G0 to use is that density / adapt_g0_divisor, clamped.
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

/// Velocity of a pose estimate: the difference between the newest estimate and the oldest one
/// within `window_s`, divided by their time difference (heading unwrapped). Zero until the
/// history spans half the window; reset when time jumps backwards or by more than the window.
class VelocityEstimator {
 public:
  explicit VelocityEstimator(double window_s = 0.1) : window_s_(window_s) {}
  void add(double t_s, const Pose2& estimate);
  /// [m/s, m/s, rad/s] in the map frame.
  const Pose2& velocity() const { return velocity_; }

 private:
  struct Sample {
    double t_s;
    Pose2 pose;  // theta unwrapped along the history
  };
  double window_s_;
  std::deque<Sample> history_;
  Pose2 velocity_;
};

class EventParticleFilter {
 public:
  /// likelihood: the cached sensor model (e.g. makeEdgeLikelihoodMap). Throws
  /// std::invalid_argument for an invalid config or an empty likelihood grid.
  EventParticleFilter(const EbpfConfig& config, const CeilingCamera& camera, GridMap2f likelihood,
                      const Pose2& start);

  /// Processes events in order, in batches of B (a trailing partial batch is processed as a
  /// smaller batch with its own decay factors). All events are validated first: an event outside
  /// the sensor or a timestamp earlier than the previous one throws std::invalid_argument and
  /// nothing of the call is processed. An empty span is a no-op.
  void process(const Event* events, std::size_t count);
  void process(const EventVector& events) { process(events.data(), events.size()); }

  /// Current pose estimate (config.filter.estimate), extrapolated by
  /// config.filter.latency_compensation_s.
  Pose2 estimate() const;
  /// The filtered pose without latency compensation.
  Pose2 rawEstimate() const;
  /// Changes the runtime knobs (particle count N, batch size B, resampling interval K, ...)
  /// without losing the filter's state: a changed N restarts the particles at the current
  /// estimate with the new config's initial spread; the G0 schedule follows the new config
  /// (an adapted G0 is kept). Throws std::invalid_argument (and changes nothing) for an invalid
  /// config.
  void setFilterConfig(const EventFilterConfig& filter);
  const ParticleSet2D& particles() const { return particles_; }
  std::uint64_t processedEvents() const { return processed_; }
  double alpha() const { return schedule_.alpha; }
  const Diffusion& diffusion() const { return schedule_.diffusion; }
  const GridMap2f& likelihood() const { return likelihood_; }
  const EbpfConfig& config() const { return config_; }
  /// G0 in use (changes with config.filter.adapt_g0).
  double g0() const { return schedule_.g0; }

 private:
  void setG0(double g0);

  EbpfConfig config_;
  G0Tracker g0_tracker_;
  CeilingCamera camera_;
  GridMap2f likelihood_;
  ParticleSet2D particles_;
  G0Schedule schedule_;
  VelocityEstimator velocity_;
  std::uint64_t processed_ = 0;
  int since_resample_ = 0;
  std::int64_t last_t_us_;
};

}  // namespace ebslam

#pragma once

// Event-based Particle Filter (thesis 6.4, alg. 7) for robot self-localisation under a ceiling
// with a known map (6.5): SE(2) particles, per-event diffusion motion model (eq. 6.38/6.39 with
// Delta_x, Delta_theta of eq. 6.9/6.10), sensor model from a cached distance transform of the
// ceiling's edge map (eq. 6.36/6.37), exponential-decay scores (eq. 6.29/6.30), resampling
// every K events.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "ebslam/events/event.h"
#include "ebslam/slam/ceiling_camera.h"
#include "ebslam/slam/event_filter.h"
#include "ebslam/slam/particle_set2d.h"
#include "ebslam/slam/tracking_state.h"

namespace ebslam {

/// Localisation beyond the thesis' known start (AMCL's names where they match): global
/// localisation, kidnap recovery, the odometry motion model and the published covariance.
/// Notes and the choice of the values: docs/ebslam_core.md#eb-pf-global-localisation
/// None of it changes the filter until it is asked for (globalLocalisation(), reseed(),
/// applyOdometry(), recovery_alpha_* > 0): with the defaults EB-PF is the thesis' filter.
struct EbpfLocalisationConfig {
  /// KLD sampling (Fox 2003) while the filter searches: the particle count after each
  /// resampling is the one that bounds the KL divergence of the sampled from the true posterior
  /// by kld_err with probability kld_z, over bins of kld_bin_m x kld_bin_m x kld_bin_rad,
  /// clamped to [min_particles, max_particles]. A global search starts with max_particles;
  /// once converged the filter continues with config.filter.num_particles.
  int min_particles = 500;
  int max_particles = 40000;
  double kld_err = 0.05;
  double kld_z = 0.99;  ///< upper standard normal quantile 1 - delta (AMCL: 0.99)
  double kld_bin_m = 0.1;
  double kld_bin_rad = 10.0 * M_PI / 180.0;
  /// Hypotheses are spread over the cells of the map within known_radius_m [m] of a mapped edge
  /// (the extent the map has observed), all headings.
  double known_radius_m = 0.5;
  /// Coarse-to-fine search: the sensor model's sigma [m] on the levels above the map's own (the
  /// particles are scored against the coarsest first, one level finer once their position
  /// spread falls below level_switch_ratio times the current level's sigma).
  std::vector<double> search_sigmas_m{0.04, 0.12};
  double level_switch_ratio = 1.2;
  /// Computational budget while searching: at most this many particle updates per event on
  /// average (one batch of B events is scored, the next ceil(N / budget) - 1 batches only
  /// advance the diffusion), so that N particles keep up with the eDVS on one core.
  double search_updates_per_event = 800.0;
  /// Converged: on the map's own level, position spread (RMS distance to the mean) below
  /// converged_spread_m [m] and heading spread below converged_spread_rad [rad] for
  /// converged_events events in a row, with a mean map value per event of at least
  /// converged_min_fit.
  double converged_spread_m = 0.03;
  double converged_spread_rad = 2.0 * M_PI / 180.0;
  int converged_events = 2000;
  double converged_min_fit = 0.4;
  /// A search that reached the map's own level but whose mean map value per event stays below
  /// converged_min_fit for search_restart_events events (a wrong mode won the coarse levels)
  /// starts again from max_particles fresh hypotheses.
  int search_restart_events = 40000;
  /// Kidnap detection (AMCL: recovery_alpha_slow, recovery_alpha_fast; 0 = off): per-event
  /// exponential averages of how well the particles explain the events (mean map value per
  /// event, ParticleSet2D::lastBatchMeanValue). When w_fast < recovery_ratio w_slow for
  /// recovery_events events in a row while tracking, the filter adds max_particles global
  /// hypotheses to its particles and searches again (AMCL injects random particles with
  /// probability 1 - w_fast / w_slow; one decision keeps the event filter's cheap tracking).
  double recovery_alpha_slow = 0.0;
  double recovery_alpha_fast = 0.0;
  double recovery_ratio = 0.4;
  int recovery_events = 4000;
  /// Motion gate [events/s]: the kidnap detector and the global search only use stretches of
  /// 32 B events arriving faster than this. A robot that stands still sees only background
  /// activity (0.1 Hz per pixel: 1600 events/s), which no pose explains: the detector would
  /// fire and the search would select on noise (AMCL's update_min_d / update_min_a play this
  /// role).
  double motion_min_event_rate = 5000.0;
  /// Odometry motion model (AMCL "diff" model; ParticleSet2D::applyOdometry): odom_alpha1
  /// rotation noise from rotation [rad^2/rad^2], odom_alpha2 from translation [rad^2/m^2],
  /// odom_alpha3 translation noise from translation [m^2/m^2], odom_alpha4 from rotation
  /// [m^2/rad^2].
  double odom_alpha1 = 0.005;
  double odom_alpha2 = 0.005;
  double odom_alpha3 = 0.005;
  double odom_alpha4 = 0.005;
  /// Published covariance = covariance_scale * the particles' weighted covariance + diag of the
  /// squared floors (the particle spread measures the filter's own noise, not the sensor's
  /// latency or the map's bias).
  double covariance_scale = 1.0;
  double covariance_floor_m = 0.0;
  double covariance_floor_rad = 0.0;
  std::uint64_t seed = 1;  ///< seeds the global hypotheses
  void validate() const;
};

/// EB-PF parameters: the filter plus the sensor model.
struct EbpfConfig {
  EventFilterConfig filter;
  /// gamma: sensor-model standard deviation in units of W_trig (eq. 6.37: 0.5, events are
  /// accurate to half a pixel).
  double gamma = 0.5;
  EbpfLocalisationConfig localisation;
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

  /// Re-seeds the particles around `mean` (map frame) with the covariance of (x, y, theta)
  /// [m^2, rad^2] (as rviz's "2D Pose Estimate"), config.filter.num_particles of them, and
  /// tracks from there. Throws std::invalid_argument (and changes nothing) for a non-finite pose
  /// or a covariance that is not symmetric positive semi-definite.
  void reseed(const Pose2& mean, const Eigen::Matrix3d& covariance);
  /// Global localisation: max_particles hypotheses uniformly over the map's known extent and all
  /// headings; the state becomes kGlobalSearch until the particles converge. keep_current: the
  /// current particles stay among the hypotheses (kidnap recovery).
  void globalLocalisation(bool keep_current = false);
  /// Moves the particles by the sensor's motion since the last call, in the sensor's own frame
  /// (an odometry delta), with the odom_alpha noise; call between event batches.
  void applyOdometry(const Pose2& delta);
  /// kTracking or kGlobalSearch.
  TrackingState state() const { return state_; }
  /// Searches that converged, and kidnaps detected (recovery triggered) since construction.
  std::uint64_t convergences() const { return convergences_; }
  std::uint64_t recoveries() const { return recoveries_; }
  /// Searches restarted because they settled on a mode the events do not fit.
  std::uint64_t searchRestarts() const { return search_restarts_; }
  /// Exponential averages of the events' fit (0 while recovery is off).
  double fitSlow() const { return w_slow_; }
  double fitFast() const { return w_fast_; }
  /// Covariance of rawEstimate() to publish (x, y, theta) [m^2, rad^2]: the particles' weighted
  /// covariance scaled and floored (EbpfLocalisationConfig::covariance_*).
  Eigen::Matrix3d covariance() const;
  /// Sensor-model level of the search (0: the map's own; i > 0: search_sigmas_m[i - 1]).
  int searchLevel() const { return level_; }
  /// The known extent's cells (centres, map frame) global hypotheses are drawn from.
  std::size_t knownCells() const { return known_cells_.size(); }

  std::uint64_t processedEvents() const { return processed_; }
  double alpha() const { return schedule_.alpha; }
  const Diffusion& diffusion() const { return schedule_.diffusion; }
  const GridMap2f& likelihood() const { return likelihood_; }
  const EbpfConfig& config() const { return config_; }
  /// G0 in use (changes with config.filter.experimental.adapt_g0).
  double g0() const { return schedule_.g0; }

 private:
  void setG0(double g0);
  void prepareSearch();
  void processValidated(const Event* events, std::size_t count);
  void trackBatches(const Event* events, std::size_t count, bool monitor);
  void processSearch(const Event* events, std::size_t count);
  void updateRecovery(double fit, int events);
  void convergedTo(int count);

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

  // Global search: coarse sensor-model levels (coarsest last), the known cells.
  std::vector<GridMap2f> levels_;
  std::vector<Eigen::Vector2f> known_cells_;
  double known_cell_m_ = 0.0;
  bool search_prepared_ = false;
  TrackingState state_ = TrackingState::kTracking;
  int level_ = 0;  // 0 = the map's own likelihood
  std::uint64_t search_rng_ = 0;
  std::uint64_t search_batches_ = 0;
  int search_since_resample_ = 0;
  int search_pending_ = 0;  // events since the last scored batch
  int converged_run_ = 0;
  double search_fit_ = 0.0;
  double w_slow_ = 0.0, w_fast_ = 0.0;
  int low_fit_run_ = 0;
  std::uint64_t search_low_fit_events_ = 0;  // events on level 0 with a low fit
  std::uint64_t convergences_ = 0, recoveries_ = 0, search_restarts_ = 0;
};

/// KLD sampling's particle count (Fox 2003, eq. 12) for k occupied bins, error bound kld_err and
/// quantile kld_z (upper standard normal quantile, e.g. 0.99 -> z = 2.326).
int kldParticleCount(int k, double kld_err, double kld_z);

}  // namespace ebslam

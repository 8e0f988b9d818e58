#pragma once

// Event-based Particle Filter (thesis 6.4, alg. 7) for robot self-localisation under a ceiling
// with a known map (6.5): SE(2) particles, per-event diffusion motion model (eq. 6.38/6.39 with
// Delta_x, Delta_theta of eq. 6.9/6.10), sensor model from a cached distance transform of the
// ceiling's edge map (eq. 6.36/6.37), exponential-decay scores (eq. 6.29/6.30), resampling
// every K events.

#include <cstddef>
#include <cstdint>
#include <deque>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "ebslam/events/event.h"
#include "ebslam/slam/ceiling_camera.h"
#include "ebslam/slam/event_filter.h"
#include "ebslam/slam/particle_set2d.h"

namespace ebslam {

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
  /// G0 in use (changes with config.filter.experimental.adapt_g0).
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

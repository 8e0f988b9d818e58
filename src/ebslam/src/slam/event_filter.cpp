#include "ebslam/slam/event_filter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ebslam {

void EventFilterConfig::validate() const {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("EventFilterConfig: " + what);
  };
  const Experimental& x = experimental;
  if (num_particles < 1) fail("num_particles must be >= 1");
  if (batch_size < 1 || batch_size > 64) fail("batch_size must lie in [1, 64]");
  if (resample_every < 1) fail("resample_every must be >= 1");
  if (!(beta > 0.0 && beta < 1.0)) fail("beta must lie in (0, 1)");
  if (!(g0 > 0.0) || !std::isfinite(g0)) fail("g0 must be positive and finite");
  if (!(x.diffusion_scale >= 0.0) || !std::isfinite(x.diffusion_scale)) {
    fail("diffusion_scale must be >= 0 and finite");
  }
  if (x.adapt_g0 && (!(x.adapt_g0_divisor > 0.0) || !(x.adapt_g0_min > 0.0) ||
                     !(x.adapt_g0_max >= x.adapt_g0_min))) {
    fail("adaptive G0 needs divisor > 0 and 0 < min <= max");
  }
  if (!(latency_compensation_s >= 0.0) || !std::isfinite(latency_compensation_s)) {
    fail("latency_compensation_s must be >= 0 and finite");
  }
  if (!(x.velocity_window_s > 0.0) || !std::isfinite(x.velocity_window_s)) {
    fail("velocity_window_s must be positive and finite");
  }
  if (!(initial_spread_m >= 0.0) || !(initial_spread_rad >= 0.0) ||
      !std::isfinite(initial_spread_m) || !std::isfinite(initial_spread_rad)) {
    fail("initial spreads must be >= 0 and finite");
  }
}

void validateEvents(const Event* events, std::size_t count, int width, int height,
                    std::int64_t& last_t_us) {
  std::int64_t t = last_t_us;
  for (std::size_t i = 0; i < count; ++i) {
    const Event& e = events[i];
    if (e.x >= width || e.y >= height) {
      throw std::invalid_argument("event " + std::to_string(i) + " at (" + std::to_string(e.x) +
                                  ", " + std::to_string(e.y) + ") lies outside the " +
                                  std::to_string(width) + "x" + std::to_string(height) + " sensor");
    }
    if (e.t_us < t) {
      throw std::invalid_argument("event " + std::to_string(i) + " has timestamp " +
                                  std::to_string(e.t_us) + " us, earlier than its predecessor (" +
                                  std::to_string(t) + " us): events must be time-ordered");
    }
    t = e.t_us;
  }
  last_t_us = t;
}

Diffusion perEventDiffusion(const EventFilterConfig& config, const CeilingCamera& camera,
                            double g0) {
  Diffusion d;
  const double scale = config.experimental.diffusion_scale;
  // eq. 6.9: Delta_x = D / (f G0); eq. 6.10: Delta_theta = 3 / (S G0) with S the sensor size.
  d.sigma_xy_m = scale * camera.wTrig() / g0;
  d.sigma_theta_rad = scale * 3.0 / (camera.width() * g0);
  return d;
}

G0Schedule makeG0Schedule(const EventFilterConfig& config, const CeilingCamera& camera, double g0) {
  G0Schedule schedule;
  schedule.g0 = g0;
  schedule.alpha = decayFromInfluence(config.beta, g0);
  schedule.diffusion = perEventDiffusion(config, camera, g0);
  for (int b = 1; b <= config.batch_size; ++b) {
    schedule.batch_decay.push_back(batchDecay(schedule.alpha, b));
  }
  return schedule;
}

G0Tracker::G0Tracker(const EventFilterConfig& config, const CeilingCamera& camera,
                     const Pose2& start)
    : w_trig_(camera.wTrig()),
      rotation_radius_px_(0.38247 * camera.width()),  // empirical factor below eq. 6.8
      divisor_(config.experimental.adapt_g0_divisor),
      min_(config.experimental.adapt_g0_min),
      max_(config.experimental.adapt_g0_max),
      window_start_(start) {}

double G0Tracker::update(std::uint64_t events, const Pose2& estimate) {
  window_events_ += events;
  // Net motion since the window start, so that estimate jitter does not count as motion.
  const double motion_px =
      std::hypot(estimate.x - window_start_.x, estimate.y - window_start_.y) / w_trig_ +
      std::abs(std::remainder(estimate.theta - window_start_.theta, 2.0 * M_PI)) *
          rotation_radius_px_;
  if (motion_px < 1.0) return 0.0;
  const double density = static_cast<double>(window_events_) / motion_px;
  smoothed_ = smoothed_ > 0.0 ? 0.7 * smoothed_ + 0.3 * density : density;
  window_start_ = estimate;
  window_events_ = 0;
  return std::clamp(smoothed_ / divisor_, min_, max_);
}

double switchFilterConfig(const EventFilterConfig& previous, const EventFilterConfig& next,
                          const G0Schedule& schedule, const Pose2& current,
                          ParticleSet2D& particles) {
  if (next.num_particles != previous.num_particles) {
    particles.reset(next.num_particles, current, next.initial_spread_m, next.initial_spread_rad,
                    1.0, next.seed);
  }
  return next.experimental.adapt_g0 && previous.experimental.adapt_g0 ? schedule.g0 : next.g0;
}

}  // namespace ebslam

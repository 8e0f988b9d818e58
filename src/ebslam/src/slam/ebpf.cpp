#include "ebslam/slam/ebpf.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace ebslam {

void EbpfConfig::validate() const {
  filter.validate();
  if (!(gamma > 0.0) || !std::isfinite(gamma)) {
    throw std::invalid_argument("EbpfConfig: gamma must be positive and finite");
  }
}

GridMap2f makeEdgeLikelihoodMap(const cv::Mat& edges, double metres_per_pixel,
                                const Eigen::Vector2d& origin_centre_m, double sigma_m) {
  if (edges.empty() || edges.type() != CV_8UC1) {
    throw std::invalid_argument("makeEdgeLikelihoodMap: edge image must be a non-empty CV_8UC1");
  }
  if (!(metres_per_pixel > 0.0) || !(sigma_m > 0.0)) {
    throw std::invalid_argument("makeEdgeLikelihoodMap: resolution and sigma must be positive");
  }
  if (cv::countNonZero(edges) == 0) {
    throw std::invalid_argument("makeEdgeLikelihoodMap: edge image has no edges");
  }
  // distanceTransform measures the distance to the nearest zero pixel: edges become zeros.
  cv::Mat not_edges = (edges == 0);
  cv::Mat distance_px;
  cv::distanceTransform(not_edges, distance_px, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  GridMap2f map(edges.cols, edges.rows, metres_per_pixel,
                origin_centre_m.x() - 0.5 * metres_per_pixel,
                origin_centre_m.y() - 0.5 * metres_per_pixel);
  const double k = -0.5 * (metres_per_pixel / sigma_m) * (metres_per_pixel / sigma_m);
  for (int r = 0; r < edges.rows; ++r) {
    const float* d = distance_px.ptr<float>(r);
    for (int c = 0; c < edges.cols; ++c) {
      map.at(c, r) = static_cast<float>(std::exp(k * d[c] * d[c]));  // eq. 6.37
    }
  }
  return map;
}

void VelocityEstimator::add(double t_s, const Pose2& estimate) {
  if (!history_.empty() && (t_s < history_.back().t_s || t_s - history_.back().t_s > window_s_)) {
    history_.clear();
    velocity_ = {};
  }
  Pose2 pose = estimate;
  if (!history_.empty()) {
    pose.theta = history_.back().pose.theta +
                 std::remainder(estimate.theta - history_.back().pose.theta, 2.0 * M_PI);
  }
  history_.push_back({t_s, pose});
  while (history_.size() > 2 && t_s - history_[1].t_s >= window_s_) history_.pop_front();
  const Sample& oldest = history_.front();
  const double span = t_s - oldest.t_s;
  if (span < 0.5 * window_s_) return;
  velocity_ = {(pose.x - oldest.pose.x) / span, (pose.y - oldest.pose.y) / span,
               (pose.theta - oldest.pose.theta) / span};
}

EventParticleFilter::EventParticleFilter(const EbpfConfig& config, const CeilingCamera& camera,
                                         GridMap2f likelihood, const Pose2& start)
    : config_(config),
      camera_(camera),
      likelihood_(std::move(likelihood)),
      velocity_(config.filter.experimental.velocity_window_s),
      last_t_us_(std::numeric_limits<std::int64_t>::min()) {
  config_.validate();
  if (likelihood_.data.empty()) {
    throw std::invalid_argument("EventParticleFilter: empty likelihood map");
  }
  const EventFilterConfig& f = config_.filter;
  setG0(f.g0);
  g0_tracker_ = G0Tracker(f, camera_, start);
  particles_.reset(f.num_particles, start, f.initial_spread_m, f.initial_spread_rad, 1.0, f.seed);
}

void EventParticleFilter::setG0(double g0) {
  schedule_ = makeG0Schedule(config_.filter, camera_, g0);
}

void EventParticleFilter::setFilterConfig(const EventFilterConfig& filter) {
  EbpfConfig next = config_;
  next.filter = filter;
  next.validate();
  const double g0 =
      switchFilterConfig(config_.filter, filter, schedule_, rawEstimate(), particles_);
  config_ = next;
  setG0(g0);
}

void EventParticleFilter::process(const Event* events, std::size_t count) {
  if (count == 0) return;
  validateEvents(events, count, camera_.width(), camera_.height(), last_t_us_);

  const EventFilterConfig& f = config_.filter;
  localiseInBatches(
      events, count, camera_, f, schedule_, likelihood_, particles_, processed_, since_resample_,
      [&](const std::uint32_t*, int, bool resampled, std::size_t batch_end) {
        if (!resampled) return;
        if (f.latency_compensation_s > 0.0) {
          velocity_.add(1e-6 * static_cast<double>(events[batch_end - 1].t_us), rawEstimate());
        }
        if (f.experimental.adapt_g0) {
          const double g0 = g0_tracker_.update(f.resample_every, estimate());
          if (g0 > 0.0) setG0(g0);
        }
      });
}

Pose2 EventParticleFilter::estimate() const {
  Pose2 p = rawEstimate();
  const double tau = config_.filter.latency_compensation_s;
  if (tau > 0.0) {
    const Pose2& v = velocity_.velocity();
    p.x += v.x * tau;
    p.y += v.y * tau;
    p.theta = std::remainder(p.theta + v.theta * tau, 2.0 * M_PI);
  }
  return p;
}

Pose2 EventParticleFilter::rawEstimate() const {
  return config_.filter.estimate == PoseEstimateMode::kBestParticle ? particles_.best()
                                                                    : particles_.weightedMean();
}

}  // namespace ebslam

#include "ebslam/slam/ebpf.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <unordered_set>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

namespace ebslam {

void EbpfLocalisationConfig::validate() const {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("EbpfLocalisationConfig: " + what);
  };
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  const auto non_negative = [](double v) { return v >= 0.0 && std::isfinite(v); };
  if (min_particles < 1 || max_particles < min_particles) {
    fail("need 1 <= min_particles <= max_particles");
  }
  if (!(kld_err > 0.0 && kld_err < 1.0)) fail("kld_err must lie in (0, 1)");
  if (!(kld_z > 0.5 && kld_z < 1.0)) fail("kld_z must lie in (0.5, 1)");
  if (!positive(kld_bin_m) || !positive(kld_bin_rad)) fail("kld bins must be positive");
  if (!positive(known_radius_m)) fail("known_radius_m must be positive");
  for (double sigma : search_sigmas_m) {
    if (!positive(sigma)) fail("search_sigmas_m must be positive");
  }
  if (!std::is_sorted(search_sigmas_m.begin(), search_sigmas_m.end())) {
    fail("search_sigmas_m must be increasing");
  }
  if (!positive(level_switch_ratio)) fail("level_switch_ratio must be positive");
  if (!(search_updates_per_event >= 1.0) || !std::isfinite(search_updates_per_event)) {
    fail("search_updates_per_event must be >= 1");
  }
  if (!positive(converged_spread_m) || !positive(converged_spread_rad)) {
    fail("converged spreads must be positive");
  }
  if (converged_events < 0 || recovery_events < 1 || search_restart_events < 1) {
    fail("converged_events must be >= 0, recovery_events and search_restart_events >= 1");
  }
  if (!non_negative(converged_min_fit)) fail("converged_min_fit must be >= 0");
  if (!(recovery_alpha_slow >= 0.0 && recovery_alpha_slow <= 1.0) ||
      !(recovery_alpha_fast >= 0.0 && recovery_alpha_fast <= 1.0)) {
    fail("recovery alphas must lie in [0, 1]");
  }
  if ((recovery_alpha_slow > 0.0) != (recovery_alpha_fast > 0.0) ||
      (recovery_alpha_slow > 0.0 && !(recovery_alpha_fast > recovery_alpha_slow))) {
    fail("recovery needs both alphas, recovery_alpha_fast > recovery_alpha_slow (0 = off)");
  }
  if (!(recovery_ratio > 0.0 && recovery_ratio < 1.0)) fail("recovery_ratio must lie in (0, 1)");
  if (!non_negative(motion_min_event_rate)) fail("motion_min_event_rate must be >= 0");
  if (!non_negative(odom_alpha1) || !non_negative(odom_alpha2) || !non_negative(odom_alpha3) ||
      !non_negative(odom_alpha4)) {
    fail("odom_alpha1..4 must be >= 0");
  }
  if (!non_negative(covariance_scale) || !non_negative(covariance_floor_m) ||
      !non_negative(covariance_floor_rad)) {
    fail("covariance_scale and floors must be >= 0");
  }
}

void EbpfConfig::validate() const {
  filter.validate();
  if (!(gamma > 0.0) || !std::isfinite(gamma)) {
    throw std::invalid_argument("EbpfConfig: gamma must be positive and finite");
  }
  localisation.validate();
}

namespace {

// Upper standard normal quantile: z with Phi(z) = p, by bisection on erfc (runs once per
// resampling of a search; 60 halvings are exact to double precision).
double normalQuantile(double p) {
  double lo = -10.0, hi = 10.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

int kldParticleCount(int k, double kld_err, double kld_z) {
  if (k <= 1) return 1;
  const double z = normalQuantile(kld_z);
  const double b = 2.0 / (9.0 * (k - 1));
  const double x = 1.0 - b + std::sqrt(b) * z;
  const double n = std::ceil((k - 1) / (2.0 * kld_err) * x * x * x);
  return n > 1e9 ? 1000000000 : static_cast<int>(n);
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
  search_rng_ = config_.localisation.seed;
}

void EventParticleFilter::prepareSearch() {
  if (search_prepared_) return;
  const EbpfLocalisationConfig& c = config_.localisation;
  const GridMap2f& fine = likelihood_;
  // Edge cells: the likelihood's peaks (1 on an edge of makeEdgeLikelihoodMap).
  float peak = 0.0f;
  for (std::size_t i = 0; i < fine.cellCount(); ++i) peak = std::max(peak, fine.data[i]);
  if (!(peak > 0.0f)) throw std::invalid_argument("EventParticleFilter: map has no edges");
  cv::Mat not_edge(fine.height, fine.width, CV_8UC1);
  for (int r = 0; r < fine.height; ++r) {
    for (int col = 0; col < fine.width; ++col) {
      not_edge.at<std::uint8_t>(r, col) = fine.at(col, r) >= 0.5f * peak ? 0 : 255;
    }
  }
  cv::Mat distance_px;
  cv::distanceTransform(not_edge, distance_px, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  const double res = fine.resolution_m;
  levels_.clear();
  for (double sigma : c.search_sigmas_m) {
    // Level grid: about sigma / 3 per cell (no finer than the map), values averaged over it.
    const int factor = std::max(1, static_cast<int>(std::floor(sigma / 3.0 / res)));
    cv::Mat value(distance_px.size(), CV_32F);
    const double k = -0.5 * (res / sigma) * (res / sigma);
    for (int r = 0; r < value.rows; ++r) {
      const float* d = distance_px.ptr<float>(r);
      float* v = value.ptr<float>(r);
      for (int col = 0; col < value.cols; ++col)
        v[col] = static_cast<float>(std::exp(k * d[col] * d[col]));
    }
    const int w = std::max(1, value.cols / factor), h = std::max(1, value.rows / factor);
    cv::Mat coarse;
    cv::resize(value, coarse, cv::Size(w, h), 0, 0, cv::INTER_AREA);
    GridMap2f level(w, h, res * value.cols / w, fine.origin_x_m, fine.origin_y_m);
    for (int r = 0; r < h; ++r) {
      for (int col = 0; col < w; ++col) level.at(col, r) = coarse.at<float>(r, col);
    }
    levels_.push_back(std::move(level));
  }
  // Known extent: cells of about 5 cm whose centre lies within known_radius_m of an edge.
  known_cell_m_ = std::max(res, 0.05);
  const int step = std::max(1, static_cast<int>(std::lround(known_cell_m_ / res)));
  known_cell_m_ = step * res;
  const float radius_px = static_cast<float>(c.known_radius_m / res);
  known_cells_.clear();
  for (int r = step / 2; r < distance_px.rows; r += step) {
    for (int col = step / 2; col < distance_px.cols; col += step) {
      if (distance_px.at<float>(r, col) <= radius_px) {
        known_cells_.emplace_back(static_cast<float>(fine.origin_x_m + (col + 0.5) * res),
                                  static_cast<float>(fine.origin_y_m + (r + 0.5) * res));
      }
    }
  }
  if (known_cells_.empty()) throw std::invalid_argument("EventParticleFilter: empty known map");
  search_prepared_ = true;
}

void EventParticleFilter::globalLocalisation(bool keep_current) {
  prepareSearch();
  const EbpfLocalisationConfig& c = config_.localisation;
  std::mt19937_64 rng(search_rng_++);
  std::uniform_int_distribution<std::size_t> cell(0, known_cells_.size() - 1);
  std::uniform_real_distribution<double> offset(-0.5 * known_cell_m_, 0.5 * known_cell_m_);
  std::uniform_real_distribution<double> heading(-M_PI, M_PI);
  std::vector<Pose2> poses(static_cast<std::size_t>(c.max_particles));
  for (Pose2& p : poses) {
    const Eigen::Vector2f& centre = known_cells_[cell(rng)];
    p.x = centre.x() + offset(rng);
    p.y = centre.y() + offset(rng);
    p.theta = heading(rng);
  }
  if (keep_current) {
    particles_.append(poses, particles_.meanScore());
  } else {
    particles_.assign(poses, 1.0);
  }
  state_ = TrackingState::kGlobalSearch;
  level_ = static_cast<int>(levels_.size());
  search_batches_ = 0;
  search_since_resample_ = 0;
  converged_run_ = 0;
  search_fit_ = 0.0;
  low_fit_run_ = 0;
  search_low_fit_events_ = 0;
}

void EventParticleFilter::reseed(const Pose2& mean, const Eigen::Matrix3d& covariance) {
  if (!std::isfinite(mean.x) || !std::isfinite(mean.y) || !std::isfinite(mean.theta)) {
    throw std::invalid_argument("EventParticleFilter::reseed: pose is not finite");
  }
  if (!covariance.allFinite() || !covariance.isApprox(covariance.transpose(), 1e-9)) {
    throw std::invalid_argument("EventParticleFilter::reseed: covariance is not finite/symmetric");
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(covariance);
  if (eig.eigenvalues().minCoeff() < -1e-12 * std::max(1.0, eig.eigenvalues().maxCoeff())) {
    throw std::invalid_argument(
        "EventParticleFilter::reseed: covariance is not positive semi-definite");
  }
  // Square root through the eigen decomposition: works for a singular covariance (rviz sends
  // zeros for the unused rows).
  const Eigen::Matrix3d root = eig.eigenvectors() *
                               eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() *
                               eig.eigenvectors().transpose();
  std::mt19937_64 rng(search_rng_++);
  std::normal_distribution<double> normal;
  std::vector<Pose2> poses(static_cast<std::size_t>(config_.filter.num_particles));
  for (Pose2& p : poses) {
    const Eigen::Vector3d d = root * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    p = {mean.x + d.x(), mean.y + d.y(), std::remainder(mean.theta + d.z(), 2.0 * M_PI)};
  }
  particles_.assign(poses, 1.0);
  state_ = TrackingState::kTracking;
  since_resample_ = 0;
  w_slow_ = w_fast_ = 0.0;
  low_fit_run_ = 0;
  velocity_ = VelocityEstimator(config_.filter.experimental.velocity_window_s);
}

void EventParticleFilter::applyOdometry(const Pose2& delta) {
  if (!std::isfinite(delta.x) || !std::isfinite(delta.y) || !std::isfinite(delta.theta)) {
    throw std::invalid_argument("EventParticleFilter::applyOdometry: delta is not finite");
  }
  const EbpfLocalisationConfig& c = config_.localisation;
  particles_.applyOdometry(delta, c.odom_alpha1, c.odom_alpha2, c.odom_alpha3, c.odom_alpha4);
}

Eigen::Matrix3d EventParticleFilter::covariance() const {
  const EbpfLocalisationConfig& c = config_.localisation;
  Eigen::Matrix3d cov = c.covariance_scale * particles_.covariance();
  cov(0, 0) += c.covariance_floor_m * c.covariance_floor_m;
  cov(1, 1) += c.covariance_floor_m * c.covariance_floor_m;
  cov(2, 2) += c.covariance_floor_rad * c.covariance_floor_rad;
  return cov;
}

void EventParticleFilter::convergedTo(int count) {
  particles_.resampleSystematic(config_.filter.experimental.reset_scores_on_resample, count);
  state_ = TrackingState::kTracking;
  ++convergences_;
  since_resample_ = 0;
  w_slow_ = w_fast_ = 0.0;
  low_fit_run_ = 0;
  velocity_ = VelocityEstimator(config_.filter.experimental.velocity_window_s);
}

void EventParticleFilter::updateRecovery(double fit, int events) {
  const EbpfLocalisationConfig& c = config_.localisation;
  if (!(c.recovery_alpha_slow > 0.0)) return;
  if (w_slow_ == 0.0) {
    w_slow_ = w_fast_ = fit;
    return;
  }
  w_slow_ += (1.0 - std::pow(1.0 - c.recovery_alpha_slow, events)) * (fit - w_slow_);
  w_fast_ += (1.0 - std::pow(1.0 - c.recovery_alpha_fast, events)) * (fit - w_fast_);
  low_fit_run_ = w_fast_ < c.recovery_ratio * w_slow_ ? low_fit_run_ + events : 0;
  if (low_fit_run_ >= c.recovery_events) {
    ++recoveries_;
    globalLocalisation(true);
  }
}

void EventParticleFilter::processSearch(const Event* events, std::size_t count) {
  const EventFilterConfig& f = config_.filter;
  const EbpfLocalisationConfig& c = config_.localisation;
  const float* ox = camera_.offsetX().data();
  const float* oy = camera_.offsetY().data();
  std::uint32_t index[64];
  const std::size_t chunk = static_cast<std::size_t>(f.batch_size) * 32;
  std::size_t i = 0;
  std::size_t chunk_end = 0;
  while (i < count && state_ == TrackingState::kGlobalSearch) {
    if (i >= chunk_end) {
      // Motion gate: a chunk of background activity only is skipped (the robot stands still).
      const std::size_t n = std::min(chunk, count - i);
      const double span_s = 1e-6 * static_cast<double>(events[i + n - 1].t_us - events[i].t_us);
      if (n >= 2 && static_cast<double>(n - 1) < c.motion_min_event_rate * span_s) {
        i += n;
        processed_ += n;
        continue;
      }
      chunk_end = i + n;
    }
    const int b = static_cast<int>(std::min<std::size_t>(f.batch_size, chunk_end - i));
    const std::size_t first = i;
    i += static_cast<std::size_t>(b);
    processed_ += static_cast<std::uint64_t>(b);
    search_pending_ += b;
    const auto n = static_cast<double>(particles_.size());
    const auto stride =
        static_cast<std::uint64_t>(std::max(1.0, std::ceil(n / c.search_updates_per_event)));
    if (++search_batches_ % stride != 0) continue;
    for (int j = 0; j < b; ++j) {
      const Event& e = events[first + static_cast<std::size_t>(j)];
      index[j] = static_cast<std::uint32_t>(e.y) * camera_.width() + e.x;
    }
    const GridMap2f& map =
        level_ == 0 ? likelihood_ : levels_[static_cast<std::size_t>(level_ - 1)];
    // The diffusion covers the motion of every event since the last scored batch (eq. 6.39).
    const double root = std::sqrt(search_pending_ * schedule_.signal_fraction);
    search_pending_ = 0;
    particles_.step(index, b, ox, oy, map, schedule_.diffusion.sigma_xy_m * root,
                    schedule_.diffusion.sigma_theta_rad * root, schedule_.batch_decay[b - 1]);
    const double fit = particles_.lastBatchMeanValue();
    search_fit_ = search_fit_ == 0.0 ? fit : search_fit_ + 0.02 * (fit - search_fit_);
    search_since_resample_ += b;
    if (search_since_resample_ < f.resample_every) continue;
    search_since_resample_ -= f.resample_every;
    // KLD sampling: the count for the bins the particles occupy.
    std::unordered_set<std::uint64_t> bins;
    for (int k = 0; k < particles_.size(); ++k) {
      if (!(particles_.score(k) > 0.0)) continue;
      const Pose2 p = particles_.particle(k);
      const auto bx = static_cast<std::int64_t>(std::floor(p.x / c.kld_bin_m));
      const auto by = static_cast<std::int64_t>(std::floor(p.y / c.kld_bin_m));
      const auto bt = static_cast<std::int64_t>(std::floor((p.theta + M_PI) / c.kld_bin_rad));
      bins.insert((static_cast<std::uint64_t>(bx & 0xFFFFFF) << 40) ^
                  (static_cast<std::uint64_t>(by & 0xFFFFFF) << 16) ^
                  static_cast<std::uint64_t>(bt & 0xFFFF));
    }
    const int target =
        std::clamp(kldParticleCount(static_cast<int>(bins.size()), c.kld_err, c.kld_z),
                   c.min_particles, c.max_particles);
    particles_.resampleSystematic(f.experimental.reset_scores_on_resample, target);
    const Eigen::Matrix3d cov = particles_.covariance();
    const double spread = std::sqrt(cov(0, 0) + cov(1, 1));
    const double spread_theta = std::sqrt(cov(2, 2));
    if (level_ > 0) {
      // The additive scores leave a cloud about as wide as the level's sigma once it has found
      // the mode: then the next finer level can take over.
      if (spread < c.level_switch_ratio * c.search_sigmas_m[static_cast<std::size_t>(level_ - 1)]) {
        --level_;
        search_fit_ = 0.0;
        converged_run_ = 0;
        search_low_fit_events_ = 0;
      }
      continue;
    }
    if (search_fit_ < c.converged_min_fit) {
      search_low_fit_events_ += static_cast<std::uint64_t>(f.resample_every) * stride;
      if (search_low_fit_events_ >= static_cast<std::uint64_t>(c.search_restart_events)) {
        ++search_restarts_;
        globalLocalisation(false);
        continue;
      }
    } else {
      search_low_fit_events_ = 0;
    }
    if (spread < c.converged_spread_m && spread_theta < c.converged_spread_rad &&
        search_fit_ >= c.converged_min_fit) {
      converged_run_ += f.resample_every;
      if (converged_run_ >= c.converged_events) convergedTo(f.num_particles);
    } else {
      converged_run_ = 0;
    }
  }
  if (i < count) processValidated(events + i, count - i);  // converged: track the rest
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
  processValidated(events, count);
}

void EventParticleFilter::processValidated(const Event* events, std::size_t count) {
  if (state_ == TrackingState::kGlobalSearch) {
    processSearch(events, count);
    return;
  }
  const EventFilterConfig& f = config_.filter;
  if (config_.localisation.recovery_alpha_slow > 0.0) {
    // Kidnap detection: chunks of whole batches (the same batches as one call), so that a
    // detected kidnap switches to the search within the call.
    const std::size_t chunk = static_cast<std::size_t>(f.batch_size) * 32;
    std::size_t i = 0;
    const double min_rate = config_.localisation.motion_min_event_rate;
    while (i < count && state_ == TrackingState::kTracking) {
      const std::size_t n = std::min(chunk, count - i);
      // Event rate of the chunk (n - 1 intervals); a chunk within one timestamp counts as fast.
      const double span_s = 1e-6 * static_cast<double>(events[i + n - 1].t_us - events[i].t_us);
      const bool moving = n >= 2 && static_cast<double>(n - 1) >= min_rate * span_s;
      trackBatches(events + i, n, moving);
      i += n;
    }
    if (i < count) processSearch(events + i, count - i);
    return;
  }
  trackBatches(events, count, false);
}

void EventParticleFilter::trackBatches(const Event* events, std::size_t count, bool monitor) {
  const EventFilterConfig& f = config_.filter;
  localiseInBatches(
      events, count, camera_, f, schedule_, likelihood_, particles_, processed_, since_resample_,
      [&](const std::uint32_t*, int b, bool resampled, std::size_t batch_end) {
        if (monitor && state_ == TrackingState::kTracking) {
          updateRecovery(particles_.lastBatchMeanValue(), b);
        }
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

#include "ebslam/slam/ebslam2d.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ebslam {

void Ebslam2dConfig::validate() const {
  filter.validate();
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("Ebslam2dConfig: " + what);
  };
  const Experimental& x = experimental;
  if (!positive(cell_size_wtrig)) fail("cell_size_wtrig must be positive");
  if (!positive(map_size_m)) fail("map_size_m must be positive");
  if (!positive(splat_sigma_wtrig)) fail("splat_sigma_wtrig must be positive");
  if (!positive(normalisation_step_px)) fail("normalisation_step_px must be positive");
  if (!positive(normalisation_prior_px)) fail("normalisation_prior_px must be positive");
  if (!positive(x.rate_window_s)) fail("rate_window_s must be positive");
  if (!(x.noise_floor_gain_down > 0.0 && x.noise_floor_gain_down <= 1.0)) {
    fail("noise_floor_gain_down must be in (0, 1]");
  }
  if (!(x.noise_floor_gain_up >= 0.0 && x.noise_floor_gain_up <= 1.0)) {
    fail("noise_floor_gain_up must be in [0, 1]");
  }
  if (!(x.noise_floor_band >= 1.0 && std::isfinite(x.noise_floor_band))) {
    fail("noise_floor_band must be >= 1");
  }
}

EventSlam2d::EventSlam2d(const Ebslam2dConfig& config, const CeilingCamera& camera,
                         const Pose2& start)
    : config_(config), camera_(camera), last_t_us_(std::numeric_limits<std::int64_t>::min()) {
  config_.validate();
  const double res = config_.cell_size_wtrig * camera_.wTrig();
  const int cells = static_cast<int>(std::ceil(config_.map_size_m / res));
  if (cells > 20000) {
    throw std::invalid_argument("Ebslam2dConfig: map of " + std::to_string(cells) +
                                " cells per side is too large (max 20000)");
  }
  const double ox = start.x - 0.5 * cells * res;
  const double oy = start.y - 0.5 * cells * res;
  occurrence_ = GridMap2f(cells, cells, res, ox, oy);
  normalisation_ = GridMap2f(cells, cells, res, ox, oy);
  map_ = GridMap2f(cells, cells, res, ox, oy);
  z0_ = static_cast<float>(config_.normalisation_prior_px);
  inverse_normalisation_ = GridMap2f(cells, cells, res, ox, oy, 1.0f / z0_);

  // Precomputed Gaussian splat kernel (7.2.4), normalised to sum 1: O counts events.
  const double sigma_cells = config_.splat_sigma_wtrig / config_.cell_size_wtrig;
  kernel_radius_ = std::max(1, static_cast<int>(std::ceil(3.0 * sigma_cells)));
  const int side = 2 * kernel_radius_ + 1;
  kernel_.resize(static_cast<std::size_t>(side) * side);
  double total = 0.0;
  for (int dy = -kernel_radius_; dy <= kernel_radius_; ++dy) {
    for (int dx = -kernel_radius_; dx <= kernel_radius_; ++dx) {
      const double w = std::exp(-0.5 * (dx * dx + dy * dy) / (sigma_cells * sigma_cells));
      kernel_[static_cast<std::size_t>(dy + kernel_radius_) * side + dx + kernel_radius_] =
          static_cast<float>(w);
      total += w;
    }
  }
  for (float& w : kernel_) w = static_cast<float>(w / total);

  const EventFilterConfig& f = config_.filter;
  setG0(f.g0);
  g0_tracker_ = G0Tracker(f, camera_, start);
  particles_.reset(f.num_particles, start, f.initial_spread_m, f.initial_spread_rad, 1.0, f.seed);
  // Noise-aware diffusion: no diffusion until the first event rate has been measured (a robot
  // starts from rest).
  if (config_.noise_aware_diffusion) schedule_.signal_fraction = 0.0;
  expected_ = HeadingVectorPose::from(start);
  last_normalised_ = expected_;
}

void EventSlam2d::setFilterConfig(const EventFilterConfig& filter) {
  Ebslam2dConfig next = config_;
  next.filter = filter;
  next.validate();
  const double g0 = switchFilterConfig(config_.filter, filter, schedule_, estimate(), particles_);
  config_ = next;
  setG0(g0);
}

void EventSlam2d::setG0(double g0) {
  const double signal_fraction = schedule_.signal_fraction;
  schedule_ = makeG0Schedule(config_.filter, camera_, g0);
  schedule_.signal_fraction = signal_fraction;
}

void EventSlam2d::updateSignalFraction(int events, std::int64_t t_us) {
  if (!rate_window_started_) {
    rate_window_started_ = true;
    rate_window_start_us_ = t_us;
    rate_window_events_ = 0;
    return;
  }
  rate_window_events_ += static_cast<std::uint64_t>(events);
  const double dt = 1e-6 * static_cast<double>(t_us - rate_window_start_us_);
  if (dt < config_.experimental.rate_window_s) return;
  const double rate = static_cast<double>(rate_window_events_) / dt;
  if (noise_floor_hz_ <= 0.0) {
    noise_floor_hz_ = rate;
  } else if (rate < noise_floor_hz_) {
    noise_floor_hz_ += config_.experimental.noise_floor_gain_down * (rate - noise_floor_hz_);
  } else if (rate < config_.experimental.noise_floor_band * noise_floor_hz_) {
    noise_floor_hz_ += config_.experimental.noise_floor_gain_up * (rate - noise_floor_hz_);
  }
  // Window rates of pure background activity scatter by 1 / sqrt(n) (Poisson): rates within two
  // standard deviations above the background estimate count as background.
  const double margin = 1.0 + 2.0 / std::sqrt(static_cast<double>(rate_window_events_));
  schedule_.signal_fraction = std::clamp(1.0 - margin * noise_floor_hz_ / rate, 0.0, 1.0);
  rate_window_start_us_ = t_us;
  rate_window_events_ = 0;
}

void EventSlam2d::process(const Event* events, std::size_t count) {
  if (count == 0) return;
  validateEvents(events, count, camera_.width(), camera_.height(), last_t_us_);

  const EventFilterConfig& f = config_.filter;
  // Localisation: EB-PF steps against the current map M (alg. 8, "update particles"), then
  // mapping after every batch.
  localiseInBatches(
      events, count, camera_, f, schedule_, map_, particles_, processed_, since_resample_,
      [&](const std::uint32_t* index, int b, bool resampled, std::size_t batch_end) {
        if (config_.noise_aware_diffusion) updateSignalFraction(b, events[batch_end - 1].t_us);
        // Mapping: occurrence splats (eq. 7.6) at the expected pose or at every particle.
        particles_.weightedMean(expected_.x, expected_.y, expected_.c, expected_.s);
        if (resampled && f.experimental.adapt_g0) {
          const double g0 = g0_tracker_.update(f.resample_every, expected_.pose());
          if (g0 > 0.0) setG0(g0);
        }
        if (config_.splat == OccurrenceSplat::kExpectedPose) {
          const Pose2 pose{expected_.x, expected_.y, 0.0};  // heading passed as (c, s)
          for (int j = 0; j < b; ++j) splat(pose, expected_.c, expected_.s, index[j], 1.0f);
        } else {
          for (int p = 0; p < particles_.size(); ++p) {
            const auto w = static_cast<float>(particles_.normalisedWeight(p));
            if (w <= 0.0f) continue;
            const Pose2 pose = particles_.particle(p);
            const double c = std::cos(pose.theta);
            const double s = std::sin(pose.theta);
            for (int j = 0; j < b; ++j) splat(pose, c, s, index[j], w);
          }
        }
        // Normalisation (eq. 7.7), periodically: once the expected pose moved the image enough.
        if (imageMotionPx(last_normalised_, expected_) >= config_.normalisation_step_px) {
          updateNormalisation(last_normalised_.pose(), expected_.pose());
          last_normalised_ = expected_;
        }
      });
}

Pose2 EventSlam2d::estimate() const {
  return config_.filter.estimate == PoseEstimateMode::kBestParticle ? particles_.best()
                                                                    : expected_.pose();
}

void EventSlam2d::splat(const Pose2& pose, double c, double s, std::uint32_t pixel, float weight) {
  const double ox = camera_.offsetX()[pixel];
  const double oy = camera_.offsetY()[pixel];
  const double wx = pose.x + c * ox - s * oy;
  const double wy = pose.y + s * ox + c * oy;
  const double inv = occurrence_.invResolution();
  const int col = static_cast<int>(std::floor((wx - occurrence_.origin_x_m) * inv));
  const int row = static_cast<int>(std::floor((wy - occurrence_.origin_y_m) * inv));
  const int r = kernel_radius_;
  if (col < r || row < r || col + r >= occurrence_.width || row + r >= occurrence_.height) {
    return;  // near or beyond the map border: dropped
  }
  const int side = 2 * r + 1;
  const float* k = kernel_.data();
  for (int dy = -r; dy <= r; ++dy) {
    const std::size_t base = static_cast<std::size_t>(row + dy) * occurrence_.width + col - r;
    for (int dx = 0; dx < side; ++dx) {
      const std::size_t cell = base + dx;
      occurrence_.data[cell] += weight * k[(dy + r) * side + dx];
      map_.data[cell] = occurrence_.data[cell] * inverse_normalisation_.data[cell];
    }
  }
}

double EventSlam2d::imageMotionPx(const HeadingVectorPose& a, const HeadingVectorPose& b) const {
  // Translation moves every pixel by |dt| / W_trig; rotation moves the outermost pixel by
  // |dtheta| times its radius.
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double cos_d = a.c * b.c + a.s * b.s;
  const double sin_d = std::abs(a.c * b.s - a.s * b.c);
  const double turn = cos_d >= 0.0 ? sin_d : M_PI;
  return (std::sqrt(dx * dx + dy * dy) + turn * camera_.footprintRadius()) / camera_.wTrig();
}

void EventSlam2d::updateNormalisation(const Pose2& from, const Pose2& to) {
  ++normalisation_updates_;
  const GridMap2f& z = normalisation_;
  const double radius = camera_.footprintRadius() + 2.0 * z.resolution_m;
  const double inv = z.invResolution();
  const double res = z.resolution_m;
  const int r0 = std::max(
      0, static_cast<int>(std::floor((std::min(from.y, to.y) - radius - z.origin_y_m) * inv)));
  const int r1 =
      std::min(z.height - 1,
               static_cast<int>(std::ceil((std::max(from.y, to.y) + radius - z.origin_y_m) * inv)));
  // Projection mu (eq. 6.1 + 6.3) inlined: camera-frame ceiling point p -> undistorted offset
  // d = p / W_trig [pixels] -> distorted pixel c + d L(|d|).
  const CameraModel& cam = camera_.camera();
  const double inv_w = 1.0 / camera_.wTrig();
  const double k1 = cam.kappa1;
  const double k2 = cam.kappa2;
  const double pcx = cam.principal_point.x();
  const double pcy = cam.principal_point.y();
  const double u_max = cam.width - 0.5;
  const double v_max = cam.height - 0.5;
  const bool eq63 = cam.distortion_model == DistortionModel::kDistortEq63 && cam.fy() == cam.fx();
  const auto project = [&](double px, double py, double& u, double& v) {
    if (!eq63) {  // another lens: the camera's own projection
      const Eigen::Vector2d e = camera_.project(Eigen::Vector2d(px, py));
      u = e.x();
      v = e.y();
    } else {
      const double dx = px * inv_w;
      const double dy = py * inv_w;
      const double rr = std::sqrt(dx * dx + dy * dy);
      const double l = 1.0 + k1 * rr + k2 * rr * rr;
      u = pcx + dx * l;
      v = pcy + dy * l;
    }
    return u >= -0.5 && v >= -0.5 && u < u_max && v < v_max;
  };
  // Rotations R(-theta) scaled in: camera coordinates of u are R(-theta) (u - t).
  const double ca = std::cos(from.theta), sa = std::sin(from.theta);
  const double cb = std::cos(to.theta), sb = std::sin(to.theta);
  const double cx_mid = 0.5 * (from.x + to.x);
  const double half_span = 0.5 * std::abs(from.x - to.x) + radius;
  if (cam.isSquarePinhole()) {
    updateNormalisationPinhole(from, to, r0, r1, cx_mid - half_span, cx_mid + half_span);
    return;
  }
  for (int r = r0; r <= r1; ++r) {
    const double wy = z.origin_y_m + (r + 0.5) * res;
    const int c0 =
        std::max(0, static_cast<int>(std::floor((cx_mid - half_span - z.origin_x_m) * inv)));
    const int c1 = std::min(z.width - 1,
                            static_cast<int>(std::ceil((cx_mid + half_span - z.origin_x_m) * inv)));
    const double ay = wy - from.y;
    const double by = wy - to.y;
    const std::size_t row = static_cast<std::size_t>(r) * z.width;
    for (int c = c0; c <= c1; ++c) {
      const double wx = z.origin_x_m + (c + 0.5) * res;
      const double ax = wx - from.x;
      const double bx = wx - to.x;
      double ua, va, ub, vb;
      // A cell not visible under both poses is not updated (7.2.3).
      if (!project(ca * ax + sa * ay, -sa * ax + ca * ay, ua, va)) continue;
      if (!project(cb * bx + sb * by, -sb * bx + cb * by, ub, vb)) continue;
      const std::size_t k = row + c;
      const double du = ua - ub;
      const double dv = va - vb;
      normalisation_.data[k] += static_cast<float>(std::sqrt(du * du + dv * dv));  // eq. 7.7
      inverse_normalisation_.data[k] = 1.0f / (normalisation_.data[k] + z0_);
      map_.data[k] = occurrence_.data[k] * inverse_normalisation_.data[k];
    }
  }
}

namespace {

// Columns c in [lo, hi] (inclusive, integers) where lo_bound <= f0 + c df < hi_bound, widened by
// one column on each side; the caller keeps the exact per-cell test.
void clipLinear(double f0, double df, double lo_bound, double hi_bound, int& lo, int& hi) {
  if (df == 0.0) {
    if (!(f0 >= lo_bound && f0 < hi_bound)) hi = lo - 1;
    return;
  }
  double a = (lo_bound - f0) / df;
  double b = (hi_bound - f0) / df;
  if (a > b) std::swap(a, b);
  lo = std::max(lo, static_cast<int>(std::max(-1e9, std::floor(a))) - 1);
  hi = std::min(hi, static_cast<int>(std::min(1e9, std::ceil(b))) + 1);
}

}  // namespace

void EventSlam2d::updateNormalisationPinhole(const Pose2& from, const Pose2& to, int r0, int r1,
                                             double x_min, double x_max) {
  // Without distortion a cell's pixel position is linear in the cell's column along a row, and
  // so is its displacement between the two poses: per row, the visible columns follow from four
  // linear inequalities and each cell costs a few multiply-adds and one square root.
  const GridMap2f& z = normalisation_;
  const CameraModel& cam = camera_.camera();
  const double inv_w = 1.0 / camera_.wTrig();
  const double res = z.resolution_m;
  const double u_lo = -0.5 - cam.principal_point.x();
  const double v_lo = -0.5 - cam.principal_point.y();
  const double u_hi = cam.width - 0.5 - cam.principal_point.x();
  const double v_hi = cam.height - 0.5 - cam.principal_point.y();
  const double ca = std::cos(from.theta) * inv_w, sa = std::sin(from.theta) * inv_w;
  const double cb = std::cos(to.theta) * inv_w, sb = std::sin(to.theta) * inv_w;
  const int c_min = std::max(0, static_cast<int>(std::floor((x_min - z.origin_x_m) / res)));
  const int c_max =
      std::min(z.width - 1, static_cast<int>(std::ceil((x_max - z.origin_x_m) / res)));
  // Offsets from the principal point [pixels] of cell column 0: ua(c) = ua0 + c dua, etc.
  const double dua = ca * res, dva = -sa * res;
  const double dub = cb * res, dvb = -sb * res;
  float* zd = normalisation_.data.data();
  float* inv_z = inverse_normalisation_.data.data();
  float* md = map_.data.data();
  const float* od = occurrence_.data.data();
  for (int r = r0; r <= r1; ++r) {
    const double wy = z.origin_y_m + (r + 0.5) * res;
    const double x0 = z.origin_x_m + 0.5 * res;
    const double ax = x0 - from.x, ay = wy - from.y;
    const double bx = x0 - to.x, by = wy - to.y;
    const double ua0 = ca * ax + sa * ay, va0 = -sa * ax + ca * ay;
    const double ub0 = cb * bx + sb * by, vb0 = -sb * bx + cb * by;
    int lo = c_min, hi = c_max;
    clipLinear(ua0, dua, u_lo, u_hi, lo, hi);
    clipLinear(va0, dva, v_lo, v_hi, lo, hi);
    clipLinear(ub0, dub, u_lo, u_hi, lo, hi);
    clipLinear(vb0, dvb, v_lo, v_hi, lo, hi);
    const std::size_t row = static_cast<std::size_t>(r) * z.width;
    // A cell not visible under both poses is not updated (7.2.3). Each coordinate is monotone
    // in c (also as rounded), so the visible cells are one run: trim clipLinear's widened
    // range to it with the exact per-cell test, then update the run without branches (which
    // vectorises; the same arithmetic per cell).
    const auto visible = [&](int c) {
      const double ua = ua0 + c * dua, va = va0 + c * dva;
      const double ub = ub0 + c * dub, vb = vb0 + c * dvb;
      return ua >= u_lo && ua < u_hi && va >= v_lo && va < v_hi && ub >= u_lo && ub < u_hi &&
             vb >= v_lo && vb < v_hi;
    };
    while (lo <= hi && !visible(lo)) ++lo;
    while (hi >= lo && !visible(hi)) --hi;
    const float z0 = z0_;
#pragma omp simd
    for (int c = lo; c <= hi; ++c) {
      const double du = (ua0 + c * dua) - (ub0 + c * dub);
      const double dv = (va0 + c * dva) - (vb0 + c * dvb);
      const std::size_t k = row + c;
      zd[k] += static_cast<float>(std::sqrt(du * du + dv * dv));  // eq. 7.7
      inv_z[k] = 1.0f / (zd[k] + z0);
      md[k] = od[k] * inv_z[k];
    }
  }
}

cv::Mat mapToImage(const GridMap2f& map, double quantile, bool dark_is_high) {
  cv::Mat image(map.height, map.width, CV_8UC1, cv::Scalar(dark_is_high ? 255 : 0));
  std::vector<float> values;
  for (std::size_t k = 0; k < map.cellCount(); ++k) {
    if (map.data[k] > 0.0f) values.push_back(map.data[k]);
  }
  if (values.empty()) return image;
  const std::size_t q =
      std::min(values.size() - 1, static_cast<std::size_t>(quantile * (values.size() - 1)));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(q), values.end());
  const float top = std::max(values[q], 1e-30f);
  for (int r = 0; r < map.height; ++r) {
    auto* row = image.ptr<std::uint8_t>(r);
    for (int c = 0; c < map.width; ++c) {
      const float v = std::min(1.0f, map.at(c, r) / top);
      const auto level = static_cast<std::uint8_t>(std::lround(255.0f * v));
      row[c] = dark_is_high ? static_cast<std::uint8_t>(255 - level) : level;
    }
  }
  return image;
}

}  // namespace ebslam

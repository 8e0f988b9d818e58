#include "ebslam/slam/particle_set2d.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ebslam {

void ParticleSet2D::reset(int n, const Pose2& start, double spread_xy_m, double spread_theta_rad,
                          double initial_score, std::uint64_t seed) {
  if (n < 1) throw std::invalid_argument("ParticleSet2D: need at least one particle");
  rng_ = FastNormalGenerator(seed);
  const auto count = static_cast<std::size_t>(n);
  x_.resize(count);
  y_.resize(count);
  cos_.resize(count);
  sin_.resize(count);
  cell_.resize(count);
  sum_.resize(count);
  noise_x_.resize(count);
  noise_y_.resize(count);
  noise_theta_.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    float g[4];
    rng_.normals4(g);
    x_[i] = static_cast<float>(start.x + spread_xy_m * g[0]);
    y_[i] = static_cast<float>(start.y + spread_xy_m * g[1]);
    const double th = start.theta + spread_theta_rad * g[2];
    cos_[i] = static_cast<float>(std::cos(th));
    sin_[i] = static_cast<float>(std::sin(th));
  }
  scores_.assign(count, initial_score);
}

void ParticleSet2D::step(const std::uint32_t* pixel_index, int batch, const float* offset_x,
                         const float* offset_y, const GridMap2f& map, double sigma_xy,
                         double sigma_theta, const BatchDecay& decay) {
  const std::size_t n = x_.size();
  float* __restrict px = x_.data();
  float* __restrict py = y_.data();
  float* __restrict pc = cos_.data();
  float* __restrict ps = sin_.data();
  // Motion model: diffusion (eq. 6.38/6.39). The heading vector turns by a small angle d with
  // cos d ~ 1 - d^2/2 and sin d ~ d (the per-batch diffusion is far below 1e-2 rad).
  const auto sxy = static_cast<float>(sigma_xy);
  const auto sth = static_cast<float>(sigma_theta);
  // The generator is serial; drawing all noise first lets the pose update below vectorise.
  float* __restrict nx = noise_x_.data();
  float* __restrict ny = noise_y_.data();
  float* __restrict nt = noise_theta_.data();
  for (std::size_t i = 0; i < n; i += 2) {
    float g[6];
    rng_.normals6(g);
    nx[i] = g[0];
    ny[i] = g[1];
    nt[i] = g[2];
    if (i + 1 < n) {
      nx[i + 1] = g[3];
      ny[i + 1] = g[4];
      nt[i + 1] = g[5];
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    px[i] += sxy * nx[i];
    py[i] += sxy * ny[i];
    const float d = sth * nt[i];
    const float cd = 1.0f - 0.5f * d * d;
    const float c = pc[i] * cd - ps[i] * d;
    const float s = ps[i] * cd + pc[i] * d;
    pc[i] = c;
    ps[i] = s;
  }
  // Sensor model: map value at each event's ceiling point under each particle's pose. Split into
  // a branch-free index loop (vectorised: the bounds test is a mask, not a branch) and a gather
  // loop; points outside the grid read the trailing 0.
  float* __restrict sum = sum_.data();
  std::uint32_t* __restrict cell = cell_.data();
  const auto inv_res = static_cast<float>(map.invResolution());
  const auto org_x = static_cast<float>(map.origin_x_m);
  const auto org_y = static_cast<float>(map.origin_y_m);
  const auto width = static_cast<float>(map.width);
  const auto height = static_cast<float>(map.height);
  const auto outside = static_cast<std::int32_t>(map.cellCount());
  const auto stride = static_cast<std::int32_t>(map.width);
  const float* data = map.data.data();
  for (int j = 0; j < batch; ++j) {
    // Map coordinates [cells]: fc = (x + c ox - s oy - org_x) / res, folded per event.
    const float ox = offset_x[pixel_index[j]] * inv_res;
    const float oy = offset_y[pixel_index[j]] * inv_res;
    const float bx = org_x * inv_res;
    const float by = org_y * inv_res;
    for (std::size_t i = 0; i < n; ++i) {
      const float fc = px[i] * inv_res + pc[i] * ox - ps[i] * oy - bx;
      const float fr = py[i] * inv_res + ps[i] * ox + pc[i] * oy - by;
      const bool in = (fc >= 0.0f) & (fr >= 0.0f) & (fc < width) & (fr < height);
      // Particles stay within metres of the map: the casts cannot overflow.
      const std::int32_t k = static_cast<std::int32_t>(fr) * stride + static_cast<std::int32_t>(fc);
      cell[i] = static_cast<std::uint32_t>(in ? k : outside);
    }
    if (j == 0) {
      for (std::size_t i = 0; i < n; ++i) sum[i] = data[cell[i]];
    } else {
      for (std::size_t i = 0; i < n; ++i) sum[i] += data[cell[i]];
    }
  }
  last_batch_ = batch;
  // Score update with the decay applied to the global scale (eq. 6.29/6.30).
  const double factor = scores_.beginUpdate(decay);
  std::vector<double>& stored = scores_.stored();
  for (std::size_t i = 0; i < n; ++i) stored[i] += factor * sum[i];
}

bool ParticleSet2D::resampleSystematic(bool reset_scores) {
  return resampleSystematic(reset_scores, size());
}

bool ParticleSet2D::resampleSystematic(bool reset_scores, int count) {
  if (count < 1) throw std::invalid_argument("ParticleSet2D: need at least one particle");
  const std::vector<double>& w = scores_.stored();
  const std::size_t n = w.size();
  const auto m = static_cast<std::size_t>(count);
  double total = 0.0;
  for (double v : w) total += v;
  if (!(total > 0.0) || !std::isfinite(total)) return false;

  scratch_x_.resize(m);
  scratch_y_.resize(m);
  scratch_c_.resize(m);
  scratch_s_.resize(m);
  scratch_w_.resize(m);
  const double step = total / static_cast<double>(m);
  double target = rng_.uniform() * step;
  double cumulative = w[0];
  std::size_t k = 0;
  for (std::size_t j = 0; j < m; ++j) {
    while (cumulative <= target && k + 1 < n) cumulative += w[++k];
    // Renormalise the heading vector here, once per resampling, against rounding drift.
    const float inv_norm = 1.0f / std::sqrt(cos_[k] * cos_[k] + sin_[k] * sin_[k]);
    scratch_x_[j] = x_[k];
    scratch_y_[j] = y_[k];
    scratch_c_[j] = cos_[k] * inv_norm;
    scratch_s_[j] = sin_[k] * inv_norm;
    scratch_w_[j] = w[k];
    target += step;
  }
  x_.swap(scratch_x_);
  y_.swap(scratch_y_);
  cos_.swap(scratch_c_);
  sin_.swap(scratch_s_);
  std::vector<double>& stored = scores_.stored();
  if (reset_scores) {
    stored.resize(m);
    std::fill(stored.begin(), stored.end(), step);
  } else {
    stored.swap(scratch_w_);
  }
  scores_.renormalise();
  if (m != n) resizeWorkspace(m);
  return true;
}

void ParticleSet2D::resizeWorkspace(std::size_t count) {
  cell_.resize(count);
  sum_.resize(count);
  noise_x_.resize(count);
  noise_y_.resize(count);
  noise_theta_.resize(count);
}

void ParticleSet2D::assign(const std::vector<Pose2>& poses, double score) {
  if (poses.empty()) throw std::invalid_argument("ParticleSet2D: need at least one particle");
  x_.clear();
  y_.clear();
  cos_.clear();
  sin_.clear();
  scores_.assign(0, score);
  append(poses, score);
}

void ParticleSet2D::append(const std::vector<Pose2>& poses, double score) {
  scores_.renormalise();
  for (const Pose2& p : poses) {
    x_.push_back(static_cast<float>(p.x));
    y_.push_back(static_cast<float>(p.y));
    cos_.push_back(static_cast<float>(std::cos(p.theta)));
    sin_.push_back(static_cast<float>(std::sin(p.theta)));
    scores_.stored().push_back(score);
  }
  resizeWorkspace(x_.size());
}

double ParticleSet2D::meanScore() const {
  if (x_.empty()) return 0.0;
  double total = 0.0;
  for (double v : scores_.stored()) total += v;
  return scores_.scale() * total / static_cast<double>(x_.size());
}

void ParticleSet2D::applyOdometry(const Pose2& delta, double alpha1, double alpha2, double alpha3,
                                  double alpha4) {
  const double trans = std::hypot(delta.x, delta.y);
  // Driving backwards is a forward motion with rot1 turned by pi: take the smaller rot1.
  double rot1 = trans < 1e-3 ? 0.0 : std::atan2(delta.y, delta.x);
  double sign = 1.0;
  if (std::abs(rot1) > 0.5 * M_PI) {
    rot1 = std::remainder(rot1 + M_PI, 2.0 * M_PI);
    sign = -1.0;
  }
  const double rot2 = std::remainder(delta.theta - rot1, 2.0 * M_PI);
  const double sd_rot1 = std::sqrt(alpha1 * rot1 * rot1 + alpha2 * trans * trans);
  const double sd_trans = std::sqrt(alpha3 * trans * trans + alpha4 * (rot1 * rot1 + rot2 * rot2));
  const double sd_rot2 = std::sqrt(alpha1 * rot2 * rot2 + alpha2 * trans * trans);
  for (std::size_t i = 0; i < x_.size(); ++i) {
    float g[4];
    rng_.normals4(g);
    const double r1 = rot1 + sd_rot1 * g[0];
    const double t = sign * (trans + sd_trans * g[1]);
    const double r2 = rot2 + sd_rot2 * g[2];
    const double heading = std::atan2(sin_[i], cos_[i]);
    const double h1 = heading + r1;
    x_[i] += static_cast<float>(t * std::cos(h1));
    y_[i] += static_cast<float>(t * std::sin(h1));
    cos_[i] = static_cast<float>(std::cos(h1 + r2));
    sin_[i] = static_cast<float>(std::sin(h1 + r2));
  }
}

double ParticleSet2D::lastBatchMeanValue() const {
  if (last_batch_ == 0 || x_.empty()) return 0.0;
  double total = 0.0;
  for (std::size_t i = 0; i < x_.size(); ++i) total += sum_[i];
  return total / (static_cast<double>(x_.size()) * last_batch_);
}

Eigen::Matrix3d ParticleSet2D::covariance() const {
  double mx = 0.0, my = 0.0, c = 1.0, s = 0.0;
  weightedMean(mx, my, c, s);
  const double mean_theta = std::atan2(s, c);
  const std::vector<double>& w = scores_.stored();
  double total = 0.0;
  for (double v : w) total += v;
  const bool plain = !(total > 0.0) || !std::isfinite(total);
  if (plain) total = static_cast<double>(x_.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < x_.size(); ++i) {
    const double wi = plain ? 1.0 : w[i];
    const Eigen::Vector3d d(x_[i] - mx, y_[i] - my,
                            std::remainder(std::atan2(sin_[i], cos_[i]) - mean_theta, 2.0 * M_PI));
    cov += wi * d * d.transpose();
  }
  return cov / total;
}

void ParticleSet2D::weightedMean(double& x, double& y, double& cos_theta, double& sin_theta) const {
  const std::vector<double>& w = scores_.stored();
  const std::size_t n = x_.size();
  double total = 0.0, sx = 0.0, sy = 0.0, sc = 0.0, ss = 0.0;
  // Runs once per batch in EB-SLAM-2D: vectorised reductions (-fopenmp-simd, no threads).
#pragma omp simd reduction(+ : total, sx, sy, sc, ss)
  for (std::size_t i = 0; i < n; ++i) {
    total += w[i];
    sx += w[i] * x_[i];
    sy += w[i] * y_[i];
    sc += w[i] * cos_[i];
    ss += w[i] * sin_[i];
  }
  if (!(total > 0.0) || !std::isfinite(total)) {  // no usable scores: plain mean
    total = static_cast<double>(n);
    sx = sy = sc = ss = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      sx += x_[i];
      sy += y_[i];
      sc += cos_[i];
      ss += sin_[i];
    }
  }
  x = sx / total;
  y = sy / total;
  const double length = std::sqrt(sc * sc + ss * ss);
  cos_theta = length > 0.0 ? sc / length : 1.0;
  sin_theta = length > 0.0 ? ss / length : 0.0;
}

Pose2 ParticleSet2D::weightedMean() const {
  Pose2 p;
  double c = 1.0, s = 0.0;
  weightedMean(p.x, p.y, c, s);
  p.theta = std::atan2(s, c);
  return p;
}

Pose2 ParticleSet2D::best() const {
  const std::vector<double>& w = scores_.stored();
  const auto it = std::max_element(w.begin(), w.end());
  return particle(static_cast<int>(it - w.begin()));
}

Pose2 ParticleSet2D::particle(int i) const {
  const auto k = static_cast<std::size_t>(i);
  return {x_[k], y_[k], std::atan2(sin_[k], cos_[k])};
}

double ParticleSet2D::normalisedWeight(int i) const {
  const std::vector<double>& w = scores_.stored();
  double total = 0.0;
  for (double v : w) total += v;
  if (!(total > 0.0)) return 0.0;
  return w[static_cast<std::size_t>(i)] / total;
}

}  // namespace ebslam

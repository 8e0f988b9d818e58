#include "ebslam/slam/ebslam3d.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

namespace ebslam {

PointEvent rayEvent(std::int64_t t_us, const Eigen::Vector3f& ray) {
  PointEvent e;
  e.t_us = t_us;
  const float norm = ray.norm();
  e.point = norm > 0.0f && std::isfinite(norm) ? Eigen::Vector3f(ray / norm) : ray;
  e.has_depth = false;
  return e;
}

Ebslam3dConfig Ebslam3dConfig::fast() {
  Ebslam3dConfig c;
  c.num_particles = 50;
  c.batch_size = 10;
  c.max_event_rate = 35000.0;
  return c;
}

Ebslam3dConfig Ebslam3dConfig::thesis() {
  Ebslam3dConfig c;
  c.num_particles = 100;
  c.batch_size = 3;
  c.resample_every = 100;
  c.event_share = 1.0;
  c.max_event_rate = 0.0;
  c.voxel_size_m = 0.01;
  c.sigma_position_m = 1e-3;
  c.sigma_rotation_rad = 1e-3;
  c.sigma_position_per_sqrt_s = 0.0;
  c.sigma_rotation_per_sqrt_s = 0.0;
  c.diffusion_min_scale = 1.0;
  c.diffusion_max_scale = 1.0;
  return c;
}

void Ebslam3dConfig::validate() const {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("Ebslam3dConfig: " + what);
  };
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (num_particles < 1 || num_particles > 100000) fail("num_particles must be in [1, 100000]");
  if (batch_size < 1 || batch_size > 64) fail("batch_size must be in [1, 64]");
  if (resample_every < 1) fail("resample_every must be at least 1");
  if (!(event_share > 0.0 && event_share <= 1.0)) fail("event_share must be in (0, 1]");
  if (!(sigma_position_m >= 0.0) || !std::isfinite(sigma_position_m)) {
    fail("sigma_position_m must be finite and >= 0");
  }
  if (!(sigma_rotation_rad >= 0.0 && sigma_rotation_rad < 1.0)) {
    fail("sigma_rotation_rad must be in [0, 1)");
  }
  if (!(max_event_rate >= 0.0) || !std::isfinite(max_event_rate)) {
    fail("max_event_rate must be finite and >= 0");
  }
  if (!positive(rate_window_s)) fail("rate_window_s must be positive");
  if (!(sigma_position_per_sqrt_s >= 0.0) || !std::isfinite(sigma_position_per_sqrt_s)) {
    fail("sigma_position_per_sqrt_s must be finite and >= 0");
  }
  if (!(sigma_rotation_per_sqrt_s >= 0.0 && sigma_rotation_per_sqrt_s < 10.0)) {
    fail("sigma_rotation_per_sqrt_s must be in [0, 10)");
  }
  if (!positive(max_diffusion_dt_s)) fail("max_diffusion_dt_s must be positive");
  if (!(diffusion_min_scale >= 0.0 && diffusion_min_scale <= diffusion_max_scale &&
        std::isfinite(diffusion_max_scale) && diffusion_max_scale <= 100.0)) {
    fail("need 0 <= diffusion_min_scale <= diffusion_max_scale <= 100");
  }
  if (!positive(reference_angular_speed) || !positive(reference_linear_speed)) {
    fail("reference_angular_speed and reference_linear_speed must be positive");
  }
  if (!positive(motion_window_s) || !positive(motion_time_s)) {
    fail("motion_window_s and motion_time_s must be positive");
  }
  if (!positive(health.fast_time_s) || !positive(health.slow_time_s) ||
      !positive(health.recover_hold_s) || !(health.warmup_s >= 0.0) ||
      !std::isfinite(health.warmup_s)) {
    fail("health: the times must be positive (warmup_s >= 0) and finite");
  }
  if (!(health.lost_fit > 0.0 && health.lost_fit <= health.recover_fit &&
        health.recover_fit <= 1.0)) {
    fail("health: need 0 < lost_fit <= recover_fit <= 1");
  }
  if (!(health.min_surface_value > 0.0) || !std::isfinite(health.min_surface_value) ||
      !(health.sample_interval_s >= 0.0) || !std::isfinite(health.sample_interval_s)) {
    fail("health: need a positive min_surface_value and a finite sample_interval_s >= 0");
  }
  if (!(health.max_event_gap_s >= 0.0) || !std::isfinite(health.max_event_gap_s)) {
    fail("health: max_event_gap_s must be finite and >= 0 (0 = off)");
  }
  if (!(rays.min_depthless_share >= 0.0 && rays.min_depthless_share <= 1.0) ||
      !positive(rays.share_time_s)) {
    fail("rays: need min_depthless_share in [0, 1] and a positive share_time_s");
  }
  if (!positive(rays.max_depth_m) || !(rays.min_map_value >= 0.0) ||
      !std::isfinite(rays.min_map_value) || !(rays.weight >= 0.0) || !std::isfinite(rays.weight)) {
    fail("rays: max_depth_m must be positive, min_map_value and weight finite and >= 0");
  }
  const RelocalisationConfig& r = relocalisation;
  if (r.particles < 1 || r.particles > 100000)
    fail("relocalisation.particles must be in [1, 100000]");
  if (!positive(r.interval_s) || !positive(r.sigma_position_m) || !positive(r.sigma_rotation_rad) ||
      !(r.growth >= 1.0) || !std::isfinite(r.growth) ||
      !(r.max_sigma_position_m >= r.sigma_position_m) || !std::isfinite(r.max_sigma_position_m) ||
      !(r.max_sigma_rotation_rad >= r.sigma_rotation_rad) || !(r.max_sigma_rotation_rad <= 3.2)) {
    fail(
        "relocalisation: need positive interval and sigmas, growth >= 1, max sigmas >= the "
        "initial ones (rotation at most 3.2 rad)");
  }
  if (!(r.elite_share >= 0.0 && r.elite_share < 1.0)) {
    fail("relocalisation.elite_share must be in [0, 1)");
  }
  if (r.candidate_keyframes < 0 || r.max_keyframes < 2 || !positive(r.keyframe_distance_m) ||
      !positive(r.keyframe_angle_rad)) {
    fail(
        "relocalisation: need candidate_keyframes >= 0, max_keyframes >= 2 and positive keyframe "
        "spacings");
  }
  if (!(score_alpha > 0.0 && score_alpha <= 1.0)) fail("score_alpha must be in (0, 1]");
  if (!positive(voxel_size_m)) fail("voxel_size_m must be positive");
  if (!positive(splat_lambda)) fail("splat_lambda must be positive");
  if (!positive(focal_px)) fail("focal_px must be positive");
  if (!(min_range_m >= 0.0) || !positive(max_range_m) || !(min_range_m < max_range_m)) {
    fail("need 0 <= min_range_m < max_range_m (finite)");
  }
  try {
    imu.gyro.validate();
  } catch (const std::invalid_argument& e) {
    fail(std::string("imu: ") + e.what());
  }
  if (!(imu.sigma_rotation_per_sqrt_s >= 0.0 && imu.sigma_rotation_per_sqrt_s < 10.0)) {
    fail("imu.sigma_rotation_per_sqrt_s must be in [0, 10)");
  }
  if (!positive(imu.bias_window_s)) fail("imu.bias_window_s must be positive");
  VoxelMapConfig map;
  map.voxel_size_m = voxel_size_m;
  map.max_memory_bytes = max_map_bytes;
  try {
    map.validate();
  } catch (const std::invalid_argument& e) {
    fail(std::string("map: ") + e.what());
  }
}

// ---------------------------------------------------------------------------------------------
// ParticleSet3D

void ParticleSet3D::reset(int n, const Pose3& start, std::uint64_t seed) {
  if (n < 1) throw std::invalid_argument("ParticleSet3D: need at least one particle");
  const auto count = static_cast<std::size_t>(n);
  const Eigen::Quaterniond q = start.orientation.normalized();
  x_.assign(count, static_cast<float>(start.position.x()));
  y_.assign(count, static_cast<float>(start.position.y()));
  z_.assign(count, static_cast<float>(start.position.z()));
  qw_.assign(count, static_cast<float>(q.w()));
  qx_.assign(count, static_cast<float>(q.x()));
  qy_.assign(count, static_cast<float>(q.y()));
  qz_.assign(count, static_cast<float>(q.z()));
  scores_.assign(count, 1.0);  // alg. 9: s_i = 1
  rng_ = FastNormalGenerator(seed);
  scratch_.resize(count * 22);  // see step()
  scratch_w_.resize(count);
}

void ParticleSet3D::assign(const std::vector<Pose3>& poses) {
  if (poses.empty()) throw std::invalid_argument("ParticleSet3D::assign: no poses");
  const std::size_t count = poses.size();
  std::vector<float>* arrays[] = {&x_, &y_, &z_, &qw_, &qx_, &qy_, &qz_};
  for (std::vector<float>* a : arrays) a->resize(count);
  Eigen::Quaterniond first = poses.front().orientation.normalized();
  for (std::size_t i = 0; i < count; ++i) {
    Eigen::Quaterniond q = poses[i].orientation.normalized();
    if (q.coeffs().dot(first.coeffs()) < 0.0) q.coeffs() = -q.coeffs();  // one hemisphere
    x_[i] = static_cast<float>(poses[i].position.x());
    y_[i] = static_cast<float>(poses[i].position.y());
    z_[i] = static_cast<float>(poses[i].position.z());
    qw_[i] = static_cast<float>(q.w());
    qx_[i] = static_cast<float>(q.x());
    qy_[i] = static_cast<float>(q.y());
    qz_[i] = static_cast<float>(q.z());
  }
  scores_.assign(count, 1.0);
  scratch_.resize(count * 22);
  scratch_w_.resize(count);
}

std::vector<int> ParticleSet3D::best(int count) const {
  const std::vector<double>& w = scores_.stored();
  std::vector<int> order(w.size());
  std::iota(order.begin(), order.end(), 0);
  const auto k = static_cast<std::size_t>(std::max(0, std::min(count, size())));
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(k), order.end(),
                    [&](int a, int b) {
                      return w[static_cast<std::size_t>(a)] > w[static_cast<std::size_t>(b)];
                    });
  order.resize(k);
  return order;
}

Pose3 ParticleSet3D::particle(int i) const {
  const auto k = static_cast<std::size_t>(i);
  Pose3 p;
  p.position = Eigen::Vector3d(x_[k], y_[k], z_[k]);
  p.orientation = Eigen::Quaterniond(qw_[k], qx_[k], qy_[k], qz_[k]).normalized();
  return p;
}

double ParticleSet3D::normalisedWeight(int i) const {
  double total = 0.0;
  for (double s : scores_.stored()) total += s;
  if (!(total > 0.0) || !std::isfinite(total)) return 1.0 / size();
  return scores_.stored()[static_cast<std::size_t>(i)] / total;
}

Pose3 ParticleSet3D::weightedMean() const {
  const std::vector<double>& w = scores_.stored();
  double total = 0.0;
  for (double s : w) total += s;
  const bool uniform = !(total > 0.0) || !std::isfinite(total);
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector4d q = Eigen::Vector4d::Zero();
  const Eigen::Vector4d ref(qw_[0], qx_[0], qy_[0], qz_[0]);
  for (std::size_t i = 0; i < x_.size(); ++i) {
    const double wi = uniform ? 1.0 : w[i];
    p += wi * Eigen::Vector3d(x_[i], y_[i], z_[i]);
    Eigen::Vector4d qi(qw_[i], qx_[i], qy_[i], qz_[i]);
    if (qi.dot(ref) < 0.0) qi = -qi;
    q += wi * qi;
  }
  const double sum = uniform ? static_cast<double>(x_.size()) : total;
  Pose3 mean;
  mean.position = p / sum;
  if (q.norm() > 1e-12) {
    q.normalize();
    mean.orientation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
  } else {
    mean.orientation = Eigen::Quaterniond(ref[0], ref[1], ref[2], ref[3]).normalized();
  }
  return mean;
}

Eigen::Matrix<double, 6, 6> ParticleSet3D::covariance(const Pose3& mean) const {
  const std::vector<double>& w = scores_.stored();
  double total = 0.0;
  for (double s : w) total += s;
  const bool uniform = !(total > 0.0) || !std::isfinite(total);
  const Eigen::Quaterniond inv_mean = mean.orientation.conjugate();
  Eigen::Matrix<double, 6, 6> c = Eigen::Matrix<double, 6, 6>::Zero();
  for (std::size_t i = 0; i < x_.size(); ++i) {
    const double wi = (uniform ? 1.0 : w[i]) / (uniform ? static_cast<double>(x_.size()) : total);
    Eigen::Quaterniond d = inv_mean * Eigen::Quaterniond(qw_[i], qx_[i], qy_[i], qz_[i]);
    if (d.w() < 0.0) d.coeffs() = -d.coeffs();
    Eigen::Matrix<double, 6, 1> v;
    v << x_[i] - mean.position.x(), y_[i] - mean.position.y(), z_[i] - mean.position.z(),
        2.0 * d.x(), 2.0 * d.y(), 2.0 * d.z();
    c += wi * v * v.transpose();
  }
  return c;
}

double ParticleSet3D::essShare() const {
  const std::vector<double>& w = scores_.stored();
  double total = 0.0, squares = 0.0;
  for (double s : w) {
    total += s;
    squares += s * s;
  }
  if (!(total > 0.0) || !std::isfinite(total) || !(squares > 0.0)) return 1.0;
  return total * total / squares / static_cast<double>(w.size());
}

float ParticleSet3D::step(const Eigen::Vector3f* points, const std::uint8_t* is_ray, int batch,
                          const ChunkedVoxelMap& map, float sigma_position, float sigma_rotation,
                          const BatchDecay& decay, float ray_weight) {
  const std::size_t n = x_.size();
  // Scratch, structure of arrays of n floats each: 7 normals, 9 rotation entries, 3 voxel
  // coordinates (as int32), the score sums, a ray's sample values and its best.
  float* g[7];
  for (int k = 0; k < 7; ++k) g[k] = scratch_.data() + k * n;
  float* rot[9];
  for (int k = 0; k < 9; ++k) rot[k] = scratch_.data() + (7 + k) * n;
  auto* ix = reinterpret_cast<std::int32_t*>(scratch_.data() + 16 * n);
  std::int32_t* iy = ix + n;
  std::int32_t* iz = iy + n;
  float* sums = scratch_.data() + 19 * n;
  float* ray_values = scratch_.data() + 20 * n;
  float* ray_best = scratch_.data() + 21 * n;
  for (std::size_t i = 0; i < n; ++i) {
    float v[8];
    rng_.normals4(v);
    rng_.normals4(v + 4);
    for (int k = 0; k < 7; ++k) g[k][i] = v[k];
  }
  float* qw = qw_.data();
  float* qxs = qx_.data();
  float* qys = qy_.data();
  float* qzs = qz_.data();
  float* xs = x_.data();
  float* ys = y_.data();
  float* zs = z_.data();
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i) {
    xs[i] += sigma_position * g[0][i];  // eq. 8.11
    ys[i] += sigma_position * g[1][i];
    zs[i] += sigma_position * g[2][i];
    // Uniform axis (eq. 8.13), normal angle, small-angle quaternion (eq. 8.15), applied in the
    // sensor frame (q <- q dq) and renormalised. The normal table holds no zero, so the axis
    // draw never vanishes; the floor only guards the division.
    const float axis_norm2 = g[3][i] * g[3][i] + g[4][i] * g[4][i] + g[5][i] * g[5][i];
    const float theta = sigma_rotation * g[6][i];
    const float s = 0.5f * theta / std::sqrt(std::max(axis_norm2, 1e-12f));
    const float dw = 1.0f - 0.25f * theta * theta;
    const float dx = s * g[3][i], dy = s * g[4][i], dz = s * g[5][i];
    const float w = qw[i], qx = qxs[i], qy = qys[i], qz = qzs[i];
    const float nw = w * dw - qx * dx - qy * dy - qz * dz;
    const float nx = w * dx + qx * dw + qy * dz - qz * dy;
    const float ny = w * dy - qx * dz + qy * dw + qz * dx;
    const float nz = w * dz + qx * dy - qy * dx + qz * dw;
    const float inv = 1.0f / std::sqrt(nw * nw + nx * nx + ny * ny + nz * nz);
    const float a = nw * inv, b = nx * inv, c = ny * inv, d = nz * inv;
    qw[i] = a;
    qxs[i] = b;
    qys[i] = c;
    qzs[i] = d;
    rot[0][i] = 1.0f - 2.0f * (c * c + d * d);
    rot[1][i] = 2.0f * (b * c - d * a);
    rot[2][i] = 2.0f * (b * d + c * a);
    rot[3][i] = 2.0f * (b * c + d * a);
    rot[4][i] = 1.0f - 2.0f * (b * b + d * d);
    rot[5][i] = 2.0f * (c * d - b * a);
    rot[6][i] = 2.0f * (b * d - c * a);
    rot[7][i] = 2.0f * (c * d + b * a);
    rot[8][i] = 1.0f - 2.0f * (b * b + c * c);
  }
  // Event-major order: the particles' views of one event lie close together, so the map finds
  // their chunk once (ChunkedVoxelMap::accumulateVoxels).
  std::fill(sums, sums + n, 0.0f);
  const float inv_voxel = static_cast<float>(1.0 / map.voxelSize());
  constexpr float kLimit = static_cast<float>(ChunkedVoxelMap::kMaxVoxelCoordinate);
  // Adds the map values of every particle's view of point e (in voxel units) to `out`.
  const auto accumulate = [&](float ex, float ey, float ez, float* out) {
    float max_abs = 0.0f;
#pragma omp simd reduction(max : max_abs)
    for (std::size_t i = 0; i < n; ++i) {
      // Map point in voxel units, clamped so that the conversion to int is defined; the clamp
      // is detected through max_abs.
      float fx = rot[0][i] * ex + rot[1][i] * ey + rot[2][i] * ez + xs[i] * inv_voxel;
      float fy = rot[3][i] * ex + rot[4][i] * ey + rot[5][i] * ez + ys[i] * inv_voxel;
      float fz = rot[6][i] * ex + rot[7][i] * ey + rot[8][i] * ez + zs[i] * inv_voxel;
      max_abs = std::max(max_abs, std::max(std::abs(fx), std::max(std::abs(fy), std::abs(fz))));
      fx = std::min(kLimit, std::max(-kLimit, fx));
      fy = std::min(kLimit, std::max(-kLimit, fy));
      fz = std::min(kLimit, std::max(-kLimit, fz));
      const auto tx = static_cast<std::int32_t>(fx);
      const auto ty = static_cast<std::int32_t>(fy);
      const auto tz = static_cast<std::int32_t>(fz);
      ix[i] = tx - (static_cast<float>(tx) > fx ? 1 : 0);  // floor
      iy[i] = ty - (static_cast<float>(ty) > fy ? 1 : 0);
      iz[i] = tz - (static_cast<float>(tz) > fz ? 1 : 0);
    }
    if (max_abs < kLimit) {
      map.accumulateVoxels(ix, iy, iz, static_cast<int>(n), out);
    }  // else: a particle far outside the map's range; its view of this event scores nothing
  };
  for (int j = 0; j < batch; ++j) {
    const float ex = points[j].x() * inv_voxel, ey = points[j].y() * inv_voxel,
                ez = points[j].z() * inv_voxel;
    if (is_ray == nullptr || is_ray[j] == 0) {
      accumulate(ex, ey, ez, sums);
      continue;
    }
    // A ray at its predicted depth: the best of three points one voxel apart along it, so that a
    // particle is not judged by the depth predicted from p_*.
    const float depth = std::sqrt(ex * ex + ey * ey + ez * ez);  // [voxels]
    if (!(depth > 1.0f)) continue;
    std::fill(ray_best, ray_best + n, 0.0f);
    for (int k = -1; k <= 1; ++k) {
      const float f = (depth + static_cast<float>(k)) / depth;
      std::fill(ray_values, ray_values + n, 0.0f);
      accumulate(f * ex, f * ey, f * ez, ray_values);
      for (std::size_t i = 0; i < n; ++i) ray_best[i] = std::max(ray_best[i], ray_values[i]);
    }
    for (std::size_t i = 0; i < n; ++i) sums[i] += ray_weight * ray_best[i];
  }
  const double factor = scores_.beginUpdate(decay);
  std::vector<double>& stored = scores_.stored();
  float best = 0.0f;
  for (std::size_t i = 0; i < n; ++i) {
    stored[i] += factor * static_cast<double>(sums[i]);
    best = std::max(best, sums[i]);
  }
  return best;
}

void ParticleSet3D::rotateBody(const Eigen::Quaternionf& delta) {
  const float dw = delta.w(), dx = delta.x(), dy = delta.y(), dz = delta.z();
  for (std::size_t i = 0; i < x_.size(); ++i) {
    const float w = qw_[i], qx = qx_[i], qy = qy_[i], qz = qz_[i];
    qw_[i] = w * dw - qx * dx - qy * dy - qz * dz;
    qx_[i] = w * dx + qx * dw + qy * dz - qz * dy;
    qy_[i] = w * dy - qx * dz + qy * dw + qz * dx;
    qz_[i] = w * dz + qx * dy - qy * dx + qz * dw;
  }
}

bool ParticleSet3D::resampleSystematic(int count) {
  std::vector<double>& w = scores_.stored();
  const std::size_t n = w.size();
  const std::size_t m = count > 0 ? static_cast<std::size_t>(count) : n;
  double total = 0.0;
  for (double s : w) total += s;
  if (!(total > 0.0) || !std::isfinite(total)) return false;
  std::vector<float>* arrays[] = {&x_, &y_, &z_, &qw_, &qx_, &qy_, &qz_};
  std::vector<float> old(7 * n);
  for (std::size_t a = 0; a < 7; ++a) std::copy(arrays[a]->begin(), arrays[a]->end(), &old[a * n]);
  const std::vector<double> old_w = w;
  if (m != n) {
    for (std::vector<float>* a : arrays) a->resize(m);
    w.resize(m);
    scratch_.resize(m * 22);
    scratch_w_.resize(m);
  }
  const double step = total / static_cast<double>(m);
  double u = rng_.uniform() * step;
  double cumulative = old_w[0];
  std::size_t k = 0;
  for (std::size_t j = 0; j < m; ++j) {
    while (u > cumulative && k + 1 < n) cumulative += old_w[++k];
    for (std::size_t a = 0; a < 7; ++a) (*arrays[a])[j] = old[a * n + k];
    w[j] = old_w[k];
    u += step;
  }
  const std::size_t n_new = m;
  // Keep the quaternions on one hemisphere of the first, so that means need no per-call flip.
  for (std::size_t j = 0; j < n_new; ++j) {
    if (qw_[j] * qw_[0] + qx_[j] * qx_[0] + qy_[j] * qy_[0] + qz_[j] * qz_[0] < 0.0f) {
      qw_[j] = -qw_[j];
      qx_[j] = -qx_[j];
      qy_[j] = -qy_[j];
      qz_[j] = -qz_[j];
    }
  }
  scores_.renormalise();
  return true;
}

// ---------------------------------------------------------------------------------------------
// EventSlam3d

namespace {

VoxelMapConfig mapConfig(const Ebslam3dConfig& c) {
  c.validate();
  VoxelMapConfig m;
  m.voxel_size_m = c.voxel_size_m;
  m.max_memory_bytes = c.max_map_bytes;
  return m;
}

}  // namespace

EventSlam3d::EventSlam3d(const Ebslam3dConfig& config, const Pose3& start)
    : config_(config), map_(mapConfig(config)), gyro_(config.imu.gyro) {
  for (int b = 1; b <= config_.batch_size; ++b) {
    batch_decay_.push_back(batchDecay(config_.score_alpha, b));
  }
  reset(start);
}

void EventSlam3d::reset(const Pose3& start) {
  map_.clear();
  particles_.reset(config_.num_particles, start, config_.seed);
  expected_ = start;
  expected_.orientation.normalize();
  in_batch_ = 0;
  share_accumulator_ = 0.0;
  since_resample_ = 0;
  have_prev_batch_ = false;
  angular_speed_ = config_.reference_angular_speed;
  linear_speed_ = config_.reference_linear_speed;
  restartMotion();
  rate_window_open_ = false;
  rate_window_count_ = 0;
  rate_share_ = 1.0;
  health_ = TrackingHealth{};
  health_started_ = false;
  next_health_sample_us_ = std::numeric_limits<std::int64_t>::min();
  have_health_sample_ = false;
  above_recover_s_ = 0.0;
  last_good_ = expected_;
  keyframes_.clear();
  keyframes_.push_back(expected_);
  search_round_ = 0;
  reseed_rng_state_ = config_.seed ^ 0x9e3779b97f4a7c15ULL;
  rays_scored_ = 0;
  rays_unscored_ = 0;
  share_started_ = false;
  last_t_us_ = std::numeric_limits<std::int64_t>::min();
  gyro_prev_set_ = false;  // gyro samples and bias are kept: they belong to the sensor
  bias_ref_set_ = false;
}

void EventSlam3d::setConfig(const Ebslam3dConfig& config) {
  config.validate();
  if (config.voxel_size_m != config_.voxel_size_m ||
      config.max_map_bytes != config_.max_map_bytes) {
    throw std::invalid_argument(
        "EventSlam3d::setConfig: voxel_size_m and max_map_bytes are fixed for a map");
  }
  const bool count_changed = config.num_particles != config_.num_particles;
  std::vector<BatchDecay> decay;
  for (int b = 1; b <= config.batch_size; ++b) decay.push_back(batchDecay(config.score_alpha, b));
  config_ = config;
  gyro_.setConfig(config_.imu.gyro);
  batch_decay_ = std::move(decay);
  // process() leaves no partial batch behind, so in_batch_ is 0 here.
  since_resample_ = std::min(since_resample_, config_.resample_every - 1);
  if (count_changed) particles_.reset(config_.num_particles, expected_, config_.seed);
}

EventSlam3d::ProcessStats EventSlam3d::process(const PointEvent* events, std::size_t count) {
  ProcessStats stats;
  if (count == 0) return stats;
  std::int64_t t = last_t_us_;
  for (std::size_t i = 0; i < count; ++i) {
    if (events[i].t_us < t) {
      throw std::invalid_argument("EventSlam3d::process: event " + std::to_string(i) +
                                  " has time " + std::to_string(events[i].t_us) +
                                  " us, earlier than its predecessor (" + std::to_string(t) +
                                  " us)");
    }
    t = events[i].t_us;
  }
  last_t_us_ = t;
  const float min_r2 = static_cast<float>(config_.min_range_m * config_.min_range_m);
  const float max_r2 = static_cast<float>(config_.max_range_m * config_.max_range_m);
  for (std::size_t i = 0; i < count; ++i) {
    const Eigen::Vector3f& p = events[i].point;
    const float r2 = p.squaredNorm();  // NaN for a non-finite point, which fails both tests
    const bool valid = events[i].has_depth ? (r2 >= min_r2 && r2 <= max_r2)
                                           : (r2 >= 0.81f && r2 <= 1.21f);  // a unit ray (10 %)
    if (!valid) {
      ++stats.rejected;
      continue;
    }
    {
      // Share of the valid events without a depth, smoothed over event time.
      const double dt =
          share_started_ ? 1e-6 * static_cast<double>(events[i].t_us - share_last_us_) : 0.0;
      share_started_ = true;
      share_last_us_ = events[i].t_us;
      const double x = events[i].has_depth ? 0.0 : 1.0;
      health_.depthless_share +=
          (1.0 - std::exp(-dt / config_.rays.share_time_s)) * (x - health_.depthless_share);
    }
    if (!events[i].has_depth &&
        (!config_.rays.enabled || health_.depthless_share < config_.rays.min_depthless_share)) {
      ++stats.rays_unscored;
      continue;
    }
    if (config_.max_event_rate > 0.0) {
      // The share for this window comes from the previous window's rate, so that the events
      // kept are spread evenly over it (a token bucket would keep each burst's first events).
      const std::int64_t t_us = events[i].t_us;
      if (!rate_window_open_) {
        rate_window_open_ = true;
        rate_window_start_us_ = t_us;
        rate_window_count_ = 0;
      } else if (static_cast<double>(t_us - rate_window_start_us_) >= 1e6 * config_.rate_window_s) {
        const double span_s = 1e-6 * static_cast<double>(t_us - rate_window_start_us_);
        const double rate = static_cast<double>(rate_window_count_) / span_s;
        rate_share_ = rate > config_.max_event_rate ? config_.max_event_rate / rate : 1.0;
        rate_window_start_us_ = t_us;
        rate_window_count_ = 0;
      }
      ++rate_window_count_;
    } else {
      rate_share_ = 1.0;
    }
    share_accumulator_ += config_.event_share * rate_share_;
    if (share_accumulator_ < 1.0) {
      ++stats.skipped;
      continue;
    }
    share_accumulator_ -= 1.0;
    batch_end_us_ = events[i].t_us;
    batch_ray_[in_batch_] = events[i].has_depth ? 0 : 1;
    batch_[in_batch_++] = p;
    ++stats.used;
    if (in_batch_ == config_.batch_size) runBatch(in_batch_, stats);
  }
  if (in_batch_ > 0) runBatch(in_batch_, stats);
  rejected_ += stats.rejected;
  rays_scored_ += stats.rays_scored;
  rays_unscored_ += stats.rays_unscored;
  return stats;
}

float EventSlam3d::predictRayDepth(const Eigen::Vector3f& ray, float min_value,
                                   float* value) const {
  // March from p_* along the ray in steps of a voxel; the depth of the strongest value.
  const Eigen::Vector3f origin = expected_.position.cast<float>();
  const Eigen::Vector3f direction = expected_.orientation.cast<float>() * ray;
  const auto step = static_cast<float>(map_.voxelSize());
  const auto near = static_cast<float>(std::max(config_.min_range_m, map_.voxelSize()));
  const auto far = static_cast<float>(std::min(config_.max_range_m, config_.rays.max_depth_m));
  float best_value = min_value;
  float best_depth = 0.0f;
  for (float s = near; s <= far; s += step) {
    const Eigen::Vector3f q = origin + s * direction;
    const float v = map_.value(q.x(), q.y(), q.z());
    if (v > best_value) {
      best_value = v;
      best_depth = s;
    }
  }
  if (value != nullptr) *value = best_value;
  return best_depth;
}

void EventSlam3d::runBatch(int b, ProcessStats& stats) {
  in_batch_ = 0;
  // Events without a depth: placed at the depth the map predicts along their ray (at p_*), or
  // dropped from the batch when nothing is mapped along it.
  int kept = 0;
  int rays = 0;
  for (int j = 0; j < b; ++j) {
    if (batch_ray_[j] != 0) {
      const float depth =
          predictRayDepth(batch_[j], static_cast<float>(config_.rays.min_map_value));
      if (!(depth > 0.0f)) {
        ++stats.rays_unscored;
        --stats.used;
        continue;
      }
      batch_[kept] = depth * batch_[j];
      ++rays;
    } else {
      batch_[kept] = batch_[j];
    }
    batch_ray_[kept] = batch_ray_[j];
    ++kept;
  }
  stats.rays_scored += static_cast<std::size_t>(rays);
  if (kept == 0) return;
  b = kept;
  // Diffusion: B events' worth (per-event part) plus the event time the batch spans (per-time
  // part), as variances.
  double dt_s = 0.0;
  if (have_prev_batch_) {
    const double gap_s = 1e-6 * static_cast<double>(batch_end_us_ - prev_batch_end_us_);
    dt_s = std::min(config_.max_diffusion_dt_s, gap_s);
    // A gap in the events: the sensor saw nothing, its motion is unknown. Searched before this
    // batch is scored (with the gyro prior the particles are then turned by its rotation over
    // the gap).
    const TrackingHealthConfig& c = config_.health;
    if (c.max_event_gap_s > 0.0 && gap_s > c.max_event_gap_s && health_started_ &&
        health_.state != TrackingState::kLost &&
        1e-6 * static_cast<double>(prev_batch_end_us_ - health_start_us_) >= c.warmup_s) {
      ++health_.event_gaps;
      enterLost();
    }
  }
  prev_batch_end_us_ = batch_end_us_;
  have_prev_batch_ = true;
  // While lost the motion is unknown: the largest diffusion.
  const bool lost = health_.state == TrackingState::kLost;
  const double scale_p = lost ? config_.diffusion_max_scale
                              : diffusionScale(linear_speed_, config_.reference_linear_speed);
  const double scale_r = lost ? config_.diffusion_max_scale
                              : diffusionScale(angular_speed_, config_.reference_angular_speed);
  const double sp = scale_p * config_.sigma_position_per_sqrt_s;
  const double sr = scale_r * config_.sigma_rotation_per_sqrt_s;
  const double var_p = b * config_.sigma_position_m * config_.sigma_position_m + dt_s * sp * sp;
  const double var_r = b * config_.sigma_rotation_rad * config_.sigma_rotation_rad + dt_s * sr * sr;
  // Gyro rotation prior: rotates the particles; the rotation diffusion around it (var_r without).
  const double var_r_batch =
      applyGyroPrior(var_r, b * config_.sigma_rotation_rad * config_.sigma_rotation_rad);
  particles_.step(batch_, batch_ray_, b, map_, static_cast<float>(std::sqrt(var_p)),
                  static_cast<float>(std::sqrt(var_r_batch)), batch_decay_[b - 1],
                  static_cast<float>(config_.rays.weight));
  processed_ += static_cast<std::uint64_t>(b);
  since_resample_ += b;
  expected_ = particles_.weightedMean();
  updateHealth(b, dt_s);
  updateGyroBias();
  if (health_.state != TrackingState::kLost) updateMotion();
  // Mapping (eq. 8.9), only while tracking: a pose that does not fit would write a wrong map.
  if (health_.state == TrackingState::kTracking) {
    updateKeyframes();
    if (config_.splat == MapSplat3d::kExpectedPose) {
      const Eigen::Quaternionf q = expected_.orientation.cast<float>();
      const Eigen::Vector3f t = expected_.position.cast<float>();
      for (int j = 0; j < b; ++j) {
        if (batch_ray_[j] == 0) splat(batch_[j], q, t, 1.0f);
      }
    } else {
      for (int i = 0; i < particles_.size(); ++i) {
        const auto w = static_cast<float>(particles_.normalisedWeight(i));
        if (!(w > 0.0f)) continue;
        const Pose3 p = particles_.particle(i);
        const Eigen::Quaternionf q = p.orientation.cast<float>();
        const Eigen::Vector3f t = p.position.cast<float>();
        for (int j = 0; j < b; ++j) {
          if (batch_ray_[j] == 0) splat(batch_[j], q, t, w);
        }
      }
    }
  }
  if (since_resample_ >= config_.resample_every) {
    particles_.resampleSystematic();
    since_resample_ -= config_.resample_every;
  }
}

double EventSlam3d::diffusionScale(double speed, double reference) const {
  return std::min(config_.diffusion_max_scale,
                  std::max(config_.diffusion_min_scale, speed / reference));
}

void EventSlam3d::restartMotion() {
  motion_window_open_ = false;
  motion_prev_set_ = false;
}

void EventSlam3d::updateMotion() {
  // Means of the estimate over windows: the rotation as a rotation vector about the window's
  // reference (the previous window's mean), so that the mean is taken in a flat chart.
  const double t_s = 1e-6 * static_cast<double>(batch_end_us_);
  if (!motion_window_open_) {
    motion_window_open_ = true;
    motion_ref_ = motion_prev_set_ ? motion_prev_mean_.orientation : expected_.orientation;
    motion_rotation_sum_.setZero();
    motion_position_sum_.setZero();
    motion_time_sum_ = 0.0;
    motion_count_ = 0;
    motion_window_start_us_ = batch_end_us_;
  }
  Eigen::Quaterniond d = motion_ref_.conjugate() * expected_.orientation;
  if (d.w() < 0.0) d.coeffs() = -d.coeffs();
  const Eigen::AngleAxisd aa(d);
  motion_rotation_sum_ += aa.angle() * aa.axis();
  motion_position_sum_ += expected_.position;
  motion_time_sum_ += t_s;
  ++motion_count_;
  const double span_s = 1e-6 * static_cast<double>(batch_end_us_ - motion_window_start_us_);
  if (span_s < config_.motion_window_s) return;
  const double inv = 1.0 / motion_count_;
  const Eigen::Vector3d mean_rotation = motion_rotation_sum_ * inv;
  Pose3 mean;
  mean.position = motion_position_sum_ * inv;
  mean.orientation = motion_ref_ * Eigen::Quaterniond(Eigen::AngleAxisd(
                                       mean_rotation.norm(), mean_rotation.norm() > 0.0
                                                                 ? mean_rotation.normalized()
                                                                 : Eigen::Vector3d::UnitZ()));
  const double mean_t_s = motion_time_sum_ * inv;
  motion_window_open_ = false;
  if (motion_prev_set_) {
    const double dt = mean_t_s - motion_prev_t_s_;
    if (dt > 0.0) {
      const double angle = mean.orientation.angularDistance(motion_prev_mean_.orientation);
      const double distance = (mean.position - motion_prev_mean_.position).norm();
      // A gap longer than a few windows (no events) says nothing about the speed within it.
      const double used_s = std::max(dt, config_.motion_window_s);
      const double gain =
          1.0 - std::exp(-std::min(dt, 4.0 * config_.motion_window_s) / config_.motion_time_s);
      angular_speed_ += gain * (angle / used_s - angular_speed_);
      linear_speed_ += gain * (distance / used_s - linear_speed_);
    }
  }
  motion_prev_mean_ = mean;
  motion_prev_t_s_ = mean_t_s;
  motion_prev_set_ = true;
}

bool EventSlam3d::fitAtEstimate(int b, double* fit, double* mapped_share) {
  if (batch_end_us_ < next_health_sample_us_) return false;
  int j = 0;
  while (j < b && batch_ray_[j] != 0) ++j;
  if (j == b) return false;
  next_health_sample_us_ =
      batch_end_us_ + static_cast<std::int64_t>(1e6 * config_.health.sample_interval_s);
  // March along the event's ray from p_* to the first mapped surface (the one the sensor sees),
  // take its peak value, and compare the event's own value (best of +-1 voxel along the ray)
  // with it.
  const Eigen::Vector3f& point = batch_[j];
  const float depth = point.norm();
  const Eigen::Vector3f origin = expected_.position.cast<float>();
  const Eigen::Vector3f direction = expected_.orientation.cast<float>() * (point / depth);
  const auto step = static_cast<float>(map_.voxelSize());
  const auto min_value = static_cast<float>(config_.health.min_surface_value);
  const auto near = static_cast<float>(std::max(config_.min_range_m, map_.voxelSize()));
  const float far =
      std::max(depth + 10.0f * step,
               static_cast<float>(std::min(config_.max_range_m, config_.rays.max_depth_m)));
  float peak = 0.0f;
  for (float s = near; s <= far; s += step) {
    const Eigen::Vector3f q = origin + s * direction;
    const float v = map_.value(q.x(), q.y(), q.z());
    if (v >= min_value) {
      peak = v;
      for (int k = 1; k <= 3; ++k) {  // the surface's peak just behind its first voxel
        const Eigen::Vector3f r = origin + (s + k * step) * direction;
        peak = std::max(peak, map_.value(r.x(), r.y(), r.z()));
      }
      break;
    }
  }
  if (!(peak > 0.0f)) {  // unexplored along this ray: no evidence
    *mapped_share = 0.0;
    return false;
  }
  *mapped_share = 1.0;
  float own = 0.0f;
  for (int k = -1; k <= 1; ++k) {
    const Eigen::Vector3f r = origin + (depth + k * step) * direction;
    own = std::max(own, map_.value(r.x(), r.y(), r.z()));
  }
  *fit = std::min(1.0, static_cast<double>(own / peak));
  return true;
}

void EventSlam3d::updateHealth(int b, double dt_s) {
  const TrackingHealthConfig& c = config_.health;
  TrackingHealth& h = health_;
  h.ess_share = particles_.essShare();
  if (h.state == TrackingState::kLost) h.time_lost_s += dt_s;
  double fit = 0.0, mapped_share = h.mapped_share;  // kept without depth events
  const bool due = batch_end_us_ >= next_health_sample_us_;
  const bool evidence = fitAtEstimate(b, &fit, &mapped_share);
  // Smoothing per sample: the time since the previous one (capped like the diffusion's).
  const double sample_dt_s =
      have_health_sample_
          ? std::min(config_.max_diffusion_dt_s,
                     1e-6 * static_cast<double>(batch_end_us_ - last_health_sample_us_))
          : 0.0;
  const double fast_gain = 1.0 - std::exp(-sample_dt_s / c.fast_time_s);
  if (due && next_health_sample_us_ > batch_end_us_) {  // a sample was taken
    h.mapped_share += fast_gain * (mapped_share - h.mapped_share);
    last_health_sample_us_ = batch_end_us_;
    have_health_sample_ = true;
  }
  // Rays only, or only unexplored space: no evidence either way.
  if (!evidence) return;
  if (!health_started_) {
    health_started_ = true;
    h.fit_fast = fit;
    h.fit_slow = fit;
    health_start_us_ = batch_end_us_;
  } else {
    h.fit_fast += fast_gain * (fit - h.fit_fast);
    // Frozen unless tracking: the reference is how well the events fitted while on track.
    if (h.state == TrackingState::kTracking) {
      h.fit_slow += (1.0 - std::exp(-sample_dt_s / c.slow_time_s)) * (h.fit_fast - h.fit_slow);
    }
  }
  h.fit_ratio = h.fit_slow > 0.0 ? h.fit_fast / h.fit_slow : 1.0;
  if (1e-6 * static_cast<double>(batch_end_us_ - health_start_us_) < c.warmup_s) {
    last_good_ = expected_;
    return;
  }
  static_cast<void>(dt_s);
  const RelocalisationConfig& r = config_.relocalisation;
  switch (h.state) {
    case TrackingState::kTracking:
      if (h.fit_fast < c.lost_fit) {
        enterLost();
      } else if (h.fit_fast >= c.recover_fit) {
        last_good_ = expected_;
      }
      break;
    case TrackingState::kLost:
      if (h.fit_fast >= c.recover_fit) {
        h.state = TrackingState::kRecovering;
        above_recover_s_ = 0.0;
        // The search found a pose that fits: back to the filter's own particle count.
        if (particles_.size() != config_.num_particles) {
          if (!particles_.resampleSystematic(config_.num_particles)) {
            particles_.reset(config_.num_particles, expected_, config_.seed + search_round_);
          }
          since_resample_ = 0;
        }
        restartMotion();
      } else if (r.enabled && batch_end_us_ >= next_reseed_us_) {
        ++search_round_;
        reseed();
      }
      break;
    case TrackingState::kRecovering:
      if (h.fit_fast < c.lost_fit) {
        enterLost();
      } else if (h.fit_fast >= c.recover_fit) {
        above_recover_s_ += sample_dt_s;
        if (above_recover_s_ >= c.recover_hold_s) {
          h.state = TrackingState::kTracking;
          ++h.relocalisations;
          h.last_relocalisation_s = 1e-6 * static_cast<double>(batch_end_us_ - lost_since_us_);
          h.relocalised = true;
          last_good_ = expected_;
        }
      } else {
        above_recover_s_ = 0.0;
      }
      break;
    case TrackingState::kGlobalSearch:  // EB-PF's state; EB-SLAM-3D never enters it
      break;
  }
}

void EventSlam3d::enterLost() {
  TrackingHealth& h = health_;
  if (h.state == TrackingState::kTracking) {  // a new loss (from recovering: the same one)
    h.relocalised = false;
    lost_since_us_ = batch_end_us_;
    search_round_ = 0;
  }
  h.state = TrackingState::kLost;
  ++h.lost_count;
  if (config_.relocalisation.enabled) reseed();
}

void EventSlam3d::updateKeyframes() {
  if (health_.fit_fast < config_.health.recover_fit) return;
  const RelocalisationConfig& r = config_.relocalisation;
  const Pose3& last = keyframes_.back();
  if ((expected_.position - last.position).norm() < r.keyframe_distance_m &&
      expected_.orientation.angularDistance(last.orientation) < r.keyframe_angle_rad) {
    return;
  }
  keyframes_.push_back(expected_);
  if (static_cast<int>(keyframes_.size()) > r.max_keyframes) {
    // Thin evenly (keeps the newest): the search candidates cover the whole explored space.
    std::vector<Pose3> thinned;
    thinned.reserve(keyframes_.size() / 2 + 1);
    for (std::size_t k = keyframes_.size() % 2 == 0 ? 1 : 0; k < keyframes_.size(); k += 2) {
      thinned.push_back(keyframes_[k]);
    }
    keyframes_ = std::move(thinned);
  }
}

void EventSlam3d::reseed() {
  const RelocalisationConfig& r = config_.relocalisation;
  next_reseed_us_ = batch_end_us_ + static_cast<std::int64_t>(1e6 * r.interval_s);
  const double growth = std::pow(r.growth, search_round_);
  const double sigma_p = std::min(r.max_sigma_position_m, r.sigma_position_m * growth);
  const double sigma_r = std::min(r.max_sigma_rotation_rad, r.sigma_rotation_rad * growth);
  // Candidates: the last good pose and the keyframes nearest it (position, plus the angle at
  // 0.3 m per rad).
  std::vector<const Pose3*> candidates{&last_good_};
  std::vector<std::pair<double, std::size_t>> by_distance;
  for (std::size_t k = 0; k < keyframes_.size(); ++k) {
    const double d = (keyframes_[k].position - last_good_.position).norm() +
                     0.3 * keyframes_[k].orientation.angularDistance(last_good_.orientation);
    by_distance.emplace_back(d, k);
  }
  const auto take = std::min(by_distance.size(), static_cast<std::size_t>(r.candidate_keyframes));
  std::partial_sort(by_distance.begin(), by_distance.begin() + static_cast<std::ptrdiff_t>(take),
                    by_distance.end());
  for (std::size_t k = 0; k < take; ++k) candidates.push_back(&keyframes_[by_distance[k].second]);
  std::vector<Pose3> poses;
  poses.reserve(static_cast<std::size_t>(r.particles));
  const int elite = static_cast<int>(r.elite_share * particles_.size());
  for (int i : particles_.best(elite)) poses.push_back(particles_.particle(i));
  std::mt19937_64 rng(reseed_rng_state_);
  reseed_rng_state_ = rng();
  std::normal_distribution<double> normal;
  for (int k = static_cast<int>(poses.size()); k < r.particles; ++k) {
    // Half of the particles about the last good pose, the rest spread over the keyframes.
    const std::size_t c = candidates.size() == 1 || k % 2 == 0
                              ? 0
                              : 1 + static_cast<std::size_t>(k / 2) % (candidates.size() - 1);
    const Pose3& centre = *candidates[c];
    Pose3 p;
    p.position = centre.position + sigma_p * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    const Eigen::Vector3d v = sigma_r * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    p.orientation = (centre.orientation *
                     Eigen::Quaterniond(Eigen::AngleAxisd(
                         v.norm(), v.norm() > 0.0 ? v.normalized() : Eigen::Vector3d::UnitZ())))
                        .normalized();
    poses.push_back(p);
  }
  particles_.assign(poses);
  since_resample_ = 0;
  restartMotion();
}

void EventSlam3d::splat(const Eigen::Vector3f& point, const Eigen::Quaternionf& q,
                        const Eigen::Vector3f& t, float weight) {
  // eq. 8.10: sigma = D / (2 lambda f), D the event's distance to the camera.
  const float sigma =
      point.norm() / static_cast<float>(2.0 * config_.splat_lambda * config_.focal_px);
  map_.addGaussian(q * point + t, sigma, weight);
}

// ---- Gyro rotation prior ----

GyroPrior::AddResult EventSlam3d::addGyro(std::int64_t t_us, const Eigen::Vector3d& rate_imu) {
  if (!config_.imu.enabled) return GyroPrior::AddResult::kAccepted;  // ignored by configuration
  return gyro_.add(t_us, rate_imu);
}

double EventSlam3d::applyGyroPrior(double fallback_var, double per_event_var) {
  if (!config_.imu.enabled || gyro_.empty()) return fallback_var;  // no IMU: unchanged
  const std::int64_t t1 = batch_end_us_;
  const std::int64_t t0 = gyro_prev_us_;
  const bool have_t0 = gyro_prev_set_;
  gyro_prev_set_ = true;
  gyro_prev_us_ = t1;
  const std::optional<Eigen::Quaterniond> delta =
      have_t0 ? gyro_.deltaRotation(t0, t1) : std::nullopt;
  if (!delta) {
    ++gyro_uncovered_;
    return fallback_var;
  }
  ++gyro_predicted_;
  particles_.rotateBody(delta->cast<float>());
  const double dt_s = 1e-6 * static_cast<double>(t1 - t0);
  const double s = config_.imu.sigma_rotation_per_sqrt_s;
  return per_event_var + s * s * dt_s + gyro_.rotationVariance(dt_s, t1);
}

void EventSlam3d::updateGyroBias() {
  if (!config_.imu.enabled || gyro_.empty()) return;
  if (config_.imu.estimate_bias) {
    // Windows of the filter's own rotation while it tracks; a window restarts after a loss.
    if (health_.state != TrackingState::kTracking) {
      bias_ref_set_ = false;
    } else if (!bias_ref_set_) {
      bias_ref_set_ = true;
      bias_ref_us_ = batch_end_us_;
      bias_ref_orientation_ = expected_.orientation;
    } else if (1e-6 * static_cast<double>(batch_end_us_ - bias_ref_us_) >=
               config_.imu.bias_window_s) {
      gyro_.updateBias(bias_ref_us_, batch_end_us_,
                       bias_ref_orientation_.conjugate() * expected_.orientation);
      bias_ref_us_ = batch_end_us_;
      bias_ref_orientation_ = expected_.orientation;
    }
  }
  gyro_.discardBefore(bias_ref_set_ ? std::min(bias_ref_us_, gyro_prev_us_) : gyro_prev_us_);
}

// ---- end gyro rotation prior ----

std::size_t EventSlam3d::memoryBytes() const {
  return map_.memoryBytes() +
         static_cast<std::size_t>(particles_.size()) * (22 * sizeof(float) + 2 * sizeof(double)) +
         keyframes_.capacity() * sizeof(Pose3);
}

std::size_t EventSlam3d::peakMemoryBytes() const {
  const int most = std::max(config_.num_particles,
                            config_.relocalisation.enabled ? config_.relocalisation.particles : 0);
  return map_.peakMemoryBytes() +
         static_cast<std::size_t>(most) * (22 * sizeof(float) + 2 * sizeof(double)) +
         static_cast<std::size_t>(config_.relocalisation.max_keyframes + 1) * sizeof(Pose3);
}

}  // namespace ebslam

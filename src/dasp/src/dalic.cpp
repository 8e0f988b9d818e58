// Density-Adaptive Local Iterative Clustering (thesis §2.4, alg. 3) with the metrics of ASP
// (def. 7) and DASP (eq. 3.19-3.21), plane-fit cluster normals (§3.2.3), purge of tiny clusters
// and count control.
#include "dasp/dalic.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "dasp/density.h"
#include "parallel.h"
#include "run_sums.h"

#include "dalic_kernels.h"  // last: see there

namespace dasp {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr int kChunks = 16;  // fixed row stripes of the assignment
// Fixed row stripes of the update, each with its own accumulators (same reductions for any
// thread count); few, because zeroing and summing them costs K * stripes.
constexpr int kUpdateChunks = 2;
// A cluster's points define a plane if their second principal variance is at least this
// fraction of the first (a strip 2 by 10 pixels gives 0.25 / 8.25 = 0.03).
constexpr float kMinPlaneSpread = 0.01f;
constexpr int kNormalSteps = 4;  // power-iteration steps of the plane normal

// Plane normal of a cluster (eq. 3.22): the eigenvector of the smallest eigenvalue l0 of the
// points' covariance. It is the dominant eigenvector of the adjugate (eigenvalues l1 l2 >=
// l0 l2 >= l0 l1), found by power iteration from the cluster's previous normal; each step
// shrinks the error by l0 / l1, which is tiny on the nearly flat patches superpixels are, so a
// few steps replace a full eigendecomposition (a per-cluster cost, which makes DASP's runtime
// grow with K). Points on a line (a superpixel squeezed into one pixel column, as on
// steep surfaces at the image border; l1 under about 1 % of l2) define no plane: their "normal"
// would be any direction across the line and push every pixel away, so `normal` is kept.
void planeNormal(const Eigen::Matrix3f& cov, Eigen::Vector3f& normal) {
  const float a = cov(0, 0), b = cov(0, 1), c = cov(0, 2), d = cov(1, 1), e = cov(1, 2),
              f = cov(2, 2);
  Eigen::Matrix3f adjugate;
  adjugate << d * f - e * e, c * e - b * f, b * e - c * d,  //
      c * e - b * f, a * f - c * c, b * c - a * e,          //
      b * e - c * d, b * c - a * e, a * d - b * b;
  const float trace = a + d + f;                  // l0 + l1 + l2
  const float adjugate_trace = adjugate.trace();  // l0 l1 + l0 l2 + l1 l2, about l1 l2
  if (!(adjugate_trace > kMinPlaneSpread * trace * trace)) return;
  // Scaled by 1 / trace, the adjugate's largest eigenvalue is in [1/3, 1]: the steps need no
  // normalisation in between (the length stays in [3^-kNormalSteps, 1]), which would put a
  // square root and a division on this per-cluster chain of dependent steps.
  adjugate *= 1.0f / adjugate_trace;
  Eigen::Vector3f x = normal;
  for (int step = 0; step < kNormalSteps; ++step) x = adjugate * x;
  const float length = x.norm();
  if (!(length > 0.0f) || !std::isfinite(length)) return;  // start orthogonal to the normal
  normal = x * (1.0f / length);
}

}  // namespace

struct Dalic::Impl {
  static ClusterTerms terms(const Dalic& self, const Cluster& c, int id) {
    const PixelFeatures& f = self.features_;
    const DalicParams& p = self.params_;
    ClusterTerms t{};
    t.id = id;
    // Integer bounding box of the disc |u - u_i| <= C R + 1 px (alg. 3; the pixel of margin
    // keeps tiny superpixels reachable), not rounded outwards further: the window's pixel count
    // per cluster pixel must not grow much as superpixels get small.
    const float half = p.window_multiple * c.radius_px + 1.0f;
    t.reach = half;
    t.x0 = std::max(0, static_cast<int>(std::ceil(c.u - half)));
    t.x1 = std::min(f.width - 1, static_cast<int>(std::floor(c.u + half)));
    t.y0 = std::max(0, static_cast<int>(std::ceil(c.v - half)));
    t.y1 = std::min(f.height - 1, static_cast<int>(std::floor(c.v + half)));
    t.u = c.u;
    t.v = c.v;
    const float wc = p.weight_color;
    t.cr = -2.0f * wc * c.color.x();
    t.cg = -2.0f * wc * c.color.y();
    t.cb = -2.0f * wc * c.color.z();
    t.offset = wc * c.color.squaredNorm();
    const bool scaled = perClusterRadius(p);
    const float radius_m =
        scaled ? radiusAtDepth(p.radius_m, c.position.z(), p.depth_exponent) : p.radius_m;
    const float inv_radius_m2 = 1.0f / (radius_m * radius_m);
    if (p.metric == MetricKind::kDepthAdaptive) {
      // The extra depth term weight_depth (z - z_i)^2 expands like the rest: the pixel's own
      // z^2 is the same for every cluster and is dropped, unless the clusters have radii of
      // their own (cxy2, cz2).
      const float spatial = p.weight_spatial * inv_radius_m2;
      const float depth_factor = 1.0f + p.weight_depth;
      t.cx = -2.0f * spatial * c.position.x();
      t.cy = -2.0f * spatial * c.position.y();
      t.cz = -2.0f * spatial * depth_factor * c.position.z();
      t.cxy2 = scaled ? spatial : 0.0f;
      t.cz2 = scaled ? spatial * depth_factor : 0.0f;
      t.cnx = -p.weight_normal * c.normal.x();
      t.cny = -p.weight_normal * c.normal.y();
      t.cnz = -p.weight_normal * c.normal.z();
      t.offset +=
          spatial * (c.position.squaredNorm() + p.weight_depth * c.position.z() * c.position.z()) +
          p.weight_normal;
    } else {
      t.spatial = p.weight_spatial / (c.radius_px * c.radius_px);
      t.depth = p.weight_spatial * inv_radius_m2;
      t.z = c.position.z();
    }
    return t;
  }

  // The pixel of a seed (rounded, clamped to the image).
  static cv::Point seedPixel(const PixelFeatures& f, const Seed& seed) {
    return {std::clamp(static_cast<int>(std::lround(seed.u)), 0, f.width - 1),
            std::clamp(static_cast<int>(std::lround(seed.v)), 0, f.height - 1)};
  }

  // The cluster of a seed: mean features of a small window around it. If the window holds no
  // valid pixel the seed is dropped: c keeps origin -1.
  static void seedCluster(const Dalic& self, const Seed& seed, int seed_index, Cluster& c) {
    const PixelFeatures& f = self.features_;
    const cv::Point centre = seedPixel(f, seed);
    const int cx = centre.x, cy = centre.y;
    const float seed_density =
        self.density_.ptr<float>()[static_cast<std::size_t>(cy) * f.width + cx];
    const float nominal =
        seed_density > 0.0f ? 1.0f / std::sqrt(kPi * seed_density) : 3.0f;  // R_rho, pixels
    const int reach = std::clamp(static_cast<int>(std::lround(0.3f * nominal)), 1, 4);
    c = Cluster{};
    c.u = static_cast<float>(cx);
    c.v = static_cast<float>(cy);
    // Plain float sums over the window (valid pixels only: invalid ones have zero features
    // but must not count).
    float sum[9] = {};
    int count = 0;
    const bool depth = f.hasDepth();
    for (int y = std::max(0, cy - reach); y <= std::min(f.height - 1, cy + reach); ++y) {
      const std::size_t base = static_cast<std::size_t>(y) * f.width;
      for (int x = std::max(0, cx - reach); x <= std::min(f.width - 1, cx + reach); ++x) {
        const std::size_t i = base + x;
        const float w = f.valid[i] ? 1.0f : 0.0f;
        count += f.valid[i];
        sum[0] += w * f.r[i];
        sum[1] += w * f.g[i];
        sum[2] += w * f.b[i];
        if (depth) {  // invalid pixels have zero points and normals
          sum[3] += f.x[i];
          sum[4] += f.y[i];
          sum[5] += f.z[i];
          sum[6] += f.nx[i];
          sum[7] += f.ny[i];
          sum[8] += f.nz[i];
        }
      }
    }
    if (count == 0) return;  // seed without any valid pixel nearby
    const Eigen::Vector3f normal_sum(sum[6], sum[7], sum[8]);
    c.color = Eigen::Vector3f(sum[0], sum[1], sum[2]) / static_cast<float>(count);
    c.position = Eigen::Vector3f(sum[3], sum[4], sum[5]) / static_cast<float>(count);
    c.normal = normal_sum.norm() > 0.0f ? Eigen::Vector3f(normal_sum.normalized())
                                        : Eigen::Vector3f(-Eigen::Vector3f::UnitZ());
    c.radius_px = radiusPx(self, c.position.z(), seed_density);
    c.mass = 1.0f;
    c.origin = seed_index;
  }

  // update(): cluster c refitted to the sums `a` of its pixels (kClusterAccSize floats, chunks
  // summed); false if it is purged (no pixel, or lighter than min_size_fraction).
  static bool refit(const Dalic& self, const float* a, Cluster& c);
  // update()'s count control: drop the lightest clusters down to `target`, or split the
  // heaviest along their principal axis up to it.
  static void dropLightest(Dalic& self, std::vector<Cluster>& next, int target);
  static void splitHeaviest(Dalic& self, std::vector<Cluster>& next, int target);

  // Projected radius of a cluster in pixels: R f / z for DASP, R_rho (def. 5) from the mean
  // density otherwise.
  static float radiusPx(const Dalic& self, float depth, float mean_density) {
    const PixelFeatures& f = self.features_;
    if (self.params_.metric == MetricKind::kDepthAdaptive && depth > 0.0f) {
      return radiusAtDepth(self.params_.radius_m, depth, self.params_.depth_exponent) * 0.5f *
             (f.intrinsics.fx + f.intrinsics.fy) / depth;
    }
    return mean_density > 0.0f ? 1.0f / std::sqrt(kPi * mean_density) : 1.0f;
  }
};

// Working memory of initialize(), assign() and update(): kept from call to call, so that the
// iterations allocate nothing once the buffers have grown to the cluster count.
struct Dalic::Scratch {
  std::vector<ClusterTerms> terms;      // assign(): the distance constants of every cluster
  std::vector<std::vector<int>> spans;  // assign(): span buckets, one per row stripe
  std::vector<int> row_stripe;          // the row stripe of each image row (set by reset())
  std::vector<std::vector<int>> stripe_clusters;  // assign(): each stripe's clusters, ascending
  std::vector<float> accumulators;  // update(): kClusterAccSize per stripe and cluster
  // update()'s output, swapped with clusters_; initialize(): one cluster per seed, in seed order
  std::vector<Cluster> next_clusters;
  std::vector<std::pair<float, int>> by_mass;  // count control: (mass, index) per cluster
  std::vector<std::uint8_t> drop;              // count control: clusters to drop
  std::vector<int> seed_row_start;             // initialize(): seeds per row, then row starts
  std::vector<int> seed_order;                 // initialize(): seed indices in row order
};

Dalic::Dalic(const PixelFeatures& features, const cv::Mat& density, const DalicParams& params)
    : features_(features),
      density_(density),
      params_(params),
      scratch_(std::make_unique<Scratch>()) {
  reset(params);
}

void Dalic::reset(const DalicParams& params) {
  const PixelFeatures& features = features_;
  const cv::Mat& density = density_;
  if (features.width <= 0 || features.height <= 0 || features.r.size() != features.size()) {
    throw std::invalid_argument("DALIC: features are empty or inconsistent");
  }
  if (density.type() != CV_32FC1 || density.cols != features.width ||
      density.rows != features.height || !density.isContinuous()) {
    throw std::invalid_argument("DALIC: density must be a continuous CV_32FC1 of the image size");
  }
  if (params.metric != MetricKind::kColor2D && !features.hasDepth()) {
    throw std::invalid_argument("DALIC: the depth metrics need features with depth");
  }
  if (params.metric != MetricKind::kColor2D && !(params.radius_m > 0.0f)) {
    throw std::invalid_argument("DALIC: radius_m must be positive for the depth metrics");
  }
  if (params.metric == MetricKind::kDepthAdaptive) {
    radiusAtDepth(params.radius_m, 1.0f, params.depth_exponent);  // throws for a bad exponent
  }
  if (!(params.window_multiple > 0.0f)) {
    throw std::invalid_argument("DALIC: window_multiple must be positive");
  }
  for (const float weight :
       {params.weight_spatial, params.weight_color, params.weight_normal, params.weight_depth}) {
    if (!(weight >= 0.0f) || !std::isfinite(weight)) {
      throw std::invalid_argument("DALIC: metric weights must be finite and >= 0");
    }
  }
  if (params.threads < 0) throw std::invalid_argument("DALIC: threads must be >= 0");
  params_ = params;
  clusters_.clear();
  if (labels_.size() != features.size()) {
    labels_.assign(features.size(), -1);
    distance_.resize(features.size());  // assign() fills it row by row
  }
  // assign()'s row stripes: the chunks forChunks runs over the rows.
  const int stripes = detail::chunkCount(features.height, kChunks);
  scratch_->row_stripe.resize(static_cast<std::size_t>(features.height));
  for (int stripe = 0; stripe < stripes; ++stripe) {
    std::fill(
        scratch_->row_stripe.begin() + detail::chunkBegin(features.height, stripes, stripe),
        scratch_->row_stripe.begin() + detail::chunkBegin(features.height, stripes, stripe + 1),
        stripe);
  }
  scratch_->spans.resize(static_cast<std::size_t>(stripes));
  scratch_->stripe_clusters.resize(static_cast<std::size_t>(stripes));
}

Dalic::~Dalic() = default;

cv::Mat Dalic::labels() const {
  return cv::Mat(features_.height, features_.width, CV_32SC1, const_cast<int*>(labels_.data()));
}

void Dalic::initialize(const std::vector<Seed>& seeds) {
  const PixelFeatures& f = features_;
  Scratch& scratch = *scratch_;
  // The seeds come in sampling order, scattered over the image, and each reads a small window
  // of ten feature arrays that do not fit in the L2 cache: visited in row order (a counting
  // sort by row), neighbouring windows share cache lines, which halves initialize() at large K.
  // The clusters keep the seed order (it decides ties in assign()).
  const std::size_t n = seeds.size();
  std::vector<int>& row_start = scratch.seed_row_start;
  row_start.assign(static_cast<std::size_t>(f.height) + 1, 0);
  for (const Seed& seed : seeds) ++row_start[static_cast<std::size_t>(Impl::seedPixel(f, seed).y)];
  int first = 0;
  for (int& start : row_start) first += std::exchange(start, first);
  std::vector<int>& order = scratch.seed_order;
  order.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    order[static_cast<std::size_t>(row_start[Impl::seedPixel(f, seeds[i]).y]++)] =
        static_cast<int>(i);
  }
  std::vector<Cluster>& built = scratch.next_clusters;
  built.resize(n);
  for (int i : order) {
    Impl::seedCluster(*this, seeds[static_cast<std::size_t>(i)], i,
                      built[static_cast<std::size_t>(i)]);
  }
  clusters_.clear();
  clusters_.reserve(n);
  for (const Cluster& c : built) {
    if (c.origin >= 0) clusters_.push_back(c);  // dropped seeds keep origin -1
  }
}

void Dalic::assign() {
  const PixelFeatures& f = features_;
  std::vector<ClusterTerms>& terms = scratch_->terms;
  terms.clear();
  for (std::size_t k = 0; k < clusters_.size(); ++k) {
    terms.push_back(Impl::terms(*this, clusters_[k], static_cast<int>(k)));
  }
  const ClusterTerms* t = terms.data();
  // The clusters whose window meets each row stripe, in ascending order: a stripe then visits
  // only those, not all K.
  const std::vector<int>& row_stripe = scratch_->row_stripe;
  std::vector<std::vector<int>>& stripe_clusters = scratch_->stripe_clusters;
  for (std::vector<int>& ids : stripe_clusters) ids.clear();  // keeps the capacity
  for (std::size_t k = 0; k < terms.size(); ++k) {
    for (int chunk = row_stripe[terms[k].y0]; chunk <= row_stripe[terms[k].y1]; ++chunk) {
      stripe_clusters[static_cast<std::size_t>(chunk)].push_back(static_cast<int>(k));
    }
  }
  float* dist = distance_.data();
  int* label = labels_.data();
  detail::forChunks(f.height, kChunks, params_.threads, [&](int chunk, int row_begin, int row_end) {
    std::vector<int>& scratch = scratch_->spans[static_cast<std::size_t>(chunk)];
    const int* ids = stripe_clusters[static_cast<std::size_t>(chunk)].data();
    const std::size_t count = stripe_clusters[static_cast<std::size_t>(chunk)].size();
    switch (params_.metric) {
      case MetricKind::kDepthAdaptive:
        if (perClusterRadius(params_)) {
          assignRowsDepthAdaptiveScaled(f, t, ids, count, row_begin, row_end, dist, label, scratch);
        } else {
          assignRowsDepthAdaptive(f, t, ids, count, row_begin, row_end, dist, label, scratch);
        }
        break;
      case MetricKind::kColor2D:
        assignRowsColor2D(f, t, ids, count, row_begin, row_end, dist, label, scratch);
        break;
      case MetricKind::kColorDepth2D:
        assignRowsColorDepth2D(f, t, ids, count, row_begin, row_end, dist, label, scratch);
        break;
    }
  });
}

void Dalic::update() {
  const PixelFeatures& f = features_;
  const std::size_t k_count = clusters_.size();
  if (k_count == 0) return;
  const bool depth = f.hasDepth();
  const std::size_t stride = static_cast<std::size_t>(kClusterAccSize) * k_count;
  std::vector<float>& accumulators = scratch_->accumulators;
  accumulators.resize(stride * kUpdateChunks);
  std::memset(accumulators.data(), 0, accumulators.size() * sizeof(float));
  const float* density = density_.ptr<float>();
  detail::forChunks(f.height, kUpdateChunks, params_.threads,
                    [&](int chunk, int row_begin, int row_end) {
                      float* acc = accumulators.data() + stride * static_cast<std::size_t>(chunk);
                      if (depth) {
                        accumulateRowsDepth(f, density, labels_.data(), clusters_.data(), row_begin,
                                            row_end, acc);
                      } else {
                        accumulateRowsColor(f, density, labels_.data(), clusters_.data(), row_begin,
                                            row_end, acc);
                      }
                    });

  std::vector<Cluster>& next = scratch_->next_clusters;
  next.clear();
  next.reserve(k_count + static_cast<std::size_t>(std::max(0, params_.target_count)));
  for (std::size_t k = 0; k < k_count; ++k) {
    // This cluster's sums over the chunks (in chunk order).
    float a[kClusterAccSize] = {};
    for (int chunk = 0; chunk < kUpdateChunks; ++chunk) {
      const float* src =
          accumulators.data() + stride * static_cast<std::size_t>(chunk) + k * kClusterAccSize;
      for (int q = 0; q < kClusterAccSize; ++q) a[q] += src[q];
    }
    Cluster c = clusters_[k];
    if (Impl::refit(*this, a, c)) next.push_back(c);
  }

  // Count control: split the heaviest clusters or drop the lightest until the target is met.
  const int target = params_.target_count;
  if (target > 0 && !next.empty()) {
    const int have = static_cast<int>(next.size());
    if (have > target) {
      Impl::dropLightest(*this, next, target);
    } else if (have < target) {
      Impl::splitHeaviest(*this, next, target);
    }
  }
  clusters_.swap(next);
}

bool Dalic::Impl::refit(const Dalic& self, const float* a, Cluster& c) {
  const float* sums = a + kRunAccSize;  // detail::RunSum order
  const float n = a[kCount];
  if (n <= 0.0f || sums[detail::kSumDensity] < self.params_.min_size_fraction) return false;
  const float inv_n = 1.0f / n;
  const float mu = a[kSu] * inv_n, mv = a[kSv] * inv_n;
  c.u += mu;
  c.v += mv;
  c.color = Eigen::Vector3f(sums[detail::kSumR], sums[detail::kSumG], sums[detail::kSumB]) * inv_n;
  c.pixel_count = static_cast<int>(n);
  c.mass = sums[detail::kSumDensity];
  // Principal 2D axis for splitting.
  const float cuu = a[kSuu] * inv_n - mu * mu;
  const float cvv = a[kSvv] * inv_n - mv * mv;
  const float cuv = a[kSuv] * inv_n - mu * mv;
  const float half_trace = 0.5f * (cuu + cvv);
  const float det_term = std::sqrt(std::max(0.0f, 0.25f * (cuu - cvv) * (cuu - cvv) + cuv * cuv));
  const float major = std::max(0.0f, half_trace + det_term);
  Eigen::Vector2f axis(major - cvv, cuv);
  if (axis.norm() < 1e-6f) axis = Eigen::Vector2f(cuv, major - cuu);
  if (axis.norm() < 1e-6f) axis = Eigen::Vector2f(1.0f, 0.0f);
  axis = axis.normalized() * std::sqrt(major);
  c.spread_u = axis.x();
  c.spread_v = axis.y();
  if (self.features_.hasDepth()) {
    const float* moments = sums + detail::kSumX;  // x, y, z, xx, xy, xz, yy, yz, zz
    const Eigen::Vector3f mean(moments[0] * inv_n, moments[1] * inv_n, moments[2] * inv_n);
    c.position += mean;
    if (n >= 4.0f) {
      Eigen::Matrix3f cov;
      cov << moments[3], moments[4], moments[5], moments[4], moments[6], moments[7], moments[5],
          moments[7], moments[8];
      cov *= inv_n;
      cov -= mean * mean.transpose();
      planeNormal(cov, c.normal);
    }  // else: too few points for a plane fit, keep the previous normal
    if (!(c.normal.norm() > 0.0f) || !c.normal.allFinite()) c.normal = -Eigen::Vector3f::UnitZ();
    c.normal.normalize();
    if (c.normal.dot(c.position) > 0.0f) c.normal = -c.normal;  // towards the camera
  }
  c.radius_px = radiusPx(self, c.position.z(), c.mass * inv_n);
  return true;
}

void Dalic::Impl::dropLightest(Dalic& self, std::vector<Cluster>& next, int target) {
  const int have = static_cast<int>(next.size());
  std::vector<std::pair<float, int>>& by_mass = self.scratch_->by_mass;
  by_mass.resize(static_cast<std::size_t>(have));
  // The lightest first, ties in index order.
  for (int i = 0; i < have; ++i) by_mass[static_cast<std::size_t>(i)] = {next[i].mass, i};
  std::sort(by_mass.begin(), by_mass.end());
  std::vector<std::uint8_t>& drop = self.scratch_->drop;
  drop.assign(next.size(), 0);
  for (int i = 0; i < have - target; ++i) drop[by_mass[static_cast<std::size_t>(i)].second] = 1;
  std::size_t kept = 0;  // compacted in place, order kept
  for (std::size_t i = 0; i < next.size(); ++i) {
    if (!drop[i]) next[kept++] = next[i];
  }
  next.resize(kept);
}

void Dalic::Impl::splitHeaviest(Dalic& self, std::vector<Cluster>& next, int target) {
  const PixelFeatures& f = self.features_;
  const bool depth = f.hasDepth();
  const int have = static_cast<int>(next.size());
  std::vector<std::pair<float, int>>& by_mass = self.scratch_->by_mass;
  by_mass.resize(static_cast<std::size_t>(have));
  // Max-heap on mass; ties broken by index for determinism.
  for (int i = 0; i < have; ++i) by_mass[static_cast<std::size_t>(i)] = {next[i].mass, -i};
  std::make_heap(by_mass.begin(), by_mass.end());  // O(K)
  for (int added = 0; added < target - have; ++added) {
    const int index = -by_mass.front().second;
    std::pop_heap(by_mass.begin(), by_mass.end());
    by_mass.pop_back();
    Cluster& parent = next[static_cast<std::size_t>(index)];
    Cluster child = parent;
    child.origin = -1;  // a new superpixel: only the parent continues the seed
    // Centroids of the two halves of a disc lie 0.85 standard deviations from its centre.
    const float su = 0.85f * parent.spread_u, sv = 0.85f * parent.spread_v;
    parent.u -= su;
    parent.v -= sv;
    child.u += su;
    child.v += sv;
    parent.mass *= 0.5f;
    child.mass *= 0.5f;
    parent.spread_u *= 0.5f;
    parent.spread_v *= 0.5f;
    child.spread_u *= 0.5f;
    child.spread_v *= 0.5f;
    for (Cluster* half : {&parent, &child}) {
      half->u = std::clamp(half->u, 0.0f, static_cast<float>(f.width - 1));
      half->v = std::clamp(half->v, 0.0f, static_cast<float>(f.height - 1));
      if (depth) {
        const std::size_t i = static_cast<std::size_t>(std::lround(half->v)) * f.width +
                              static_cast<std::size_t>(std::lround(half->u));
        if (f.valid[i]) half->position = Eigen::Vector3f(f.x[i], f.y[i], f.z[i]);
      }
    }
    const float parent_mass = parent.mass;
    next.push_back(child);  // capacity reserved by update(): no reallocation
    by_mass.push_back({parent_mass, -index});
    std::push_heap(by_mass.begin(), by_mass.end());
    by_mass.push_back({child.mass, -static_cast<int>(next.size() - 1)});
    std::push_heap(by_mass.begin(), by_mass.end());
  }
}

DalicParams dalicParams(const DaspConfig& config, MetricKind metric, float radius_m,
                        int target_count) {
  DalicParams params;
  params.metric = metric;
  params.weight_spatial = config.weight_spatial;
  params.weight_color = config.weight_color;
  params.weight_normal = config.weight_normal;
  params.weight_depth = config.experimental.weight_depth;
  params.window_multiple = config.window_multiple;
  params.radius_m = radius_m;
  params.depth_exponent =
      metric == MetricKind::kDepthAdaptive ? config.experimental.depth_exponent : 2.0f;
  params.min_size_fraction = config.min_size_fraction;
  params.target_count = target_count;
  params.threads = config.threads;
  return params;
}

DalicParams dalicParams(const AspConfig& config) {
  DalicParams params;
  params.metric = MetricKind::kColor2D;
  params.weight_spatial = config.weight_spatial;
  params.weight_color = config.weight_color;
  params.window_multiple = config.window_multiple;
  params.min_size_fraction = config.min_size_fraction;
  params.target_count = config.superpixel_count;
  params.threads = config.threads;
  return params;
}

}  // namespace dasp

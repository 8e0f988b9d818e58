// Density-Adaptive Local Iterative Clustering (thesis §2.4, alg. 3) with the metrics of ASP
// (def. 7) and DASP (eq. 3.19-3.21), plane-fit cluster normals (§3.2.3), purge of tiny clusters
// and count control.
#include <algorithm>
#include <cmath>
#include <queue>
#include <stdexcept>
#include <utility>

#include <Eigen/Eigenvalues>

#include "dasp/stages.h"
#include "parallel.h"
#include "point_moments.h"

namespace dasp {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr int kChunks = 16;  // fixed row stripes of the assignment
// Fixed row stripes of the update, each with its own accumulators (same reductions for any
// thread count); few, because zeroing and summing them costs K * stripes.
constexpr int kUpdateChunks = 4;
constexpr int kLanes = 8;  // AVX2 floats per vector: assignment spans are padded to this
constexpr float kUnreached = 1e30f;
constexpr float kInvalidPixel = -1.0f;  // distance of pixels no cluster may take

// Accumulator layout per cluster (float sums relative to the cluster's previous centre).
enum Acc : int {
  kCount,
  kSu,
  kSv,
  kSuu,
  kSvv,
  kSuv,
  kSr,
  kSg,
  kSb,
  kSx,
  kSy,
  kSz,
  kSxx,
  kSxy,
  kSxz,
  kSyy,
  kSyz,
  kSzz,
  kMass,
  kAccSize
};

// Per-cluster constants of the distance, precomputed once per assign().
struct ClusterTerms {
  int x0, x1, y0, y1;  // window, inclusive pixel bounds
  float u, v;
  float r, g, b;
  float x, y, z;
  float nx, ny, nz;
  float reach;    // radius of the disc the cluster can reach, pixels (C R + 1)
  float spatial;  // weight / radius^2 of the compactness term
  float depth;    // weight / R^2 of the depth term (kColorDepth2D)
};

// One row of the d_DA assignment (eq. 3.20) over columns x0..x1. Built for AVX2 and the
// baseline instruction set (selected at load time where the compiler supports it): this loop
// is most of DASP's runtime.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void depthAdaptiveRow(const float* __restrict r, const float* __restrict g,
                      const float* __restrict b, const float* __restrict px,
                      const float* __restrict py, const float* __restrict pz,
                      const float* __restrict nx, const float* __restrict ny,
                      const float* __restrict nz, float* __restrict d_row, int* __restrict l_row,
                      // cppcheck-suppress passedByValue ; a by-value copy keeps the terms in registers
                      int x0, int x1, int span_end, const ClusterTerms t, float wc, float wn,
                      int id) {
  for (int col = x0; col < span_end; ++col) {
    const float dx = px[col] - t.x, dy = py[col] - t.y, dz = pz[col] - t.z;
    const float dr = r[col] - t.r, dg = g[col] - t.g, db = b[col] - t.b;
    const float dot = nx[col] * t.nx + ny[col] * t.ny + nz[col] * t.nz;
    const float d = t.spatial * (dx * dx + dy * dy + dz * dz) + wc * (dr * dr + dg * dg + db * db) +
                    wn * (1.0f - dot);
    // Branch-free select so that the loop vectorises.
    const float old = d_row[col];
    const bool closer = (d < old) & (col <= x1);
    const int take = -static_cast<int>(closer);
    d_row[col] = closer ? d : old;
    l_row[col] = (l_row[col] & ~take) | (id & take);
  }
}

}  // namespace

struct Dalic::Impl {
  template <MetricKind kKind>
  static void assignRows(Dalic& self, const std::vector<ClusterTerms>& terms, int row_begin,
                         int row_end) {
    const PixelFeatures& f = self.features_;
    const int width = f.width;
    const float wc = self.params_.weight_color;
    const float wn = self.params_.weight_normal;
    float* __restrict dist = self.distance_.data();
    int* __restrict label = self.labels_.data();
    for (std::size_t k = 0; k < terms.size(); ++k) {
      const ClusterTerms t = terms[k];  // a copy: the stores below cannot alias it
      const int y0 = std::max(t.y0, row_begin);
      const int y1 = std::min(t.y1, row_end - 1);
      const int id = static_cast<int>(k);
      const float reach2 = t.reach * t.reach;
      for (int row = y0; row <= y1; ++row) {
        // Only the chord of the reach disc in this row: pixels in the corners of the bounding
        // square are farther than C R from the centre (alg. 3 tests the cluster's reach; the
        // square is the thesis' simplification, 27 % more distance evaluations).
        const float dv_c = static_cast<float>(row) - t.v;
        const float chord = std::sqrt(std::max(0.0f, reach2 - dv_c * dv_c));
        const int x0 = std::max(t.x0, static_cast<int>(std::ceil(t.u - chord)));
        const int x1 = std::min(t.x1, static_cast<int>(std::floor(t.u + chord)));
        if (x0 > x1) continue;
        // The span is rounded up to whole vectors (within the row), lanes past x1 masked out:
        // a scalar remainder loop would cost as much as the vector part on these short rows.
        const int span_end = std::min(width, x0 + ((x1 - x0 + kLanes) / kLanes) * kLanes);
        const std::size_t base = static_cast<std::size_t>(row) * width;
        const float* __restrict r = f.r.data() + base;
        const float* __restrict g = f.g.data() + base;
        const float* __restrict b = f.b.data() + base;
        float* __restrict d_row = dist + base;
        int* __restrict l_row = label + base;
        if constexpr (kKind == MetricKind::kDepthAdaptive) {
          const float* __restrict px = f.x.data() + base;
          const float* __restrict py = f.y.data() + base;
          const float* __restrict pz = f.z.data() + base;
          const float* __restrict nx = f.nx.data() + base;
          const float* __restrict ny = f.ny.data() + base;
          const float* __restrict nz = f.nz.data() + base;
          depthAdaptiveRow(r, g, b, px, py, pz, nx, ny, nz, d_row, l_row, x0, x1, span_end, t, wc,
                           wn, id);
        } else {
          const float dv = static_cast<float>(row) - t.v;
          const float dv2 = dv * dv;
          const float* __restrict pz =
              kKind == MetricKind::kColorDepth2D ? f.z.data() + base : nullptr;
          for (int col = x0; col < span_end; ++col) {
            const float du = static_cast<float>(col) - t.u;
            const float dr = r[col] - t.r, dg = g[col] - t.g, db = b[col] - t.b;
            float d = t.spatial * (du * du + dv2) + wc * (dr * dr + dg * dg + db * db);
            if constexpr (kKind == MetricKind::kColorDepth2D) {
              const float dz = pz[col] - t.z;
              d += t.depth * dz * dz;
            }
            // Branch-free select so that the loop vectorises.
            const float old = d_row[col];
            const bool closer = (d < old) & (col <= x1);
            const int take = -static_cast<int>(closer);
            d_row[col] = closer ? d : old;
            l_row[col] = (l_row[col] & ~take) | (id & take);
          }
        }
      }
    }
  }

  static ClusterTerms terms(const Dalic& self, const Cluster& c) {
    const PixelFeatures& f = self.features_;
    const DalicParams& p = self.params_;
    ClusterTerms t{};
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
    t.r = c.color.x();
    t.g = c.color.y();
    t.b = c.color.z();
    t.x = c.position.x();
    t.y = c.position.y();
    t.z = c.position.z();
    t.nx = c.normal.x();
    t.ny = c.normal.y();
    t.nz = c.normal.z();
    const float radius_m2 = p.radius_m * p.radius_m;
    if (p.metric == MetricKind::kDepthAdaptive) {
      t.spatial = p.weight_spatial / radius_m2;
    } else {
      t.spatial = p.weight_spatial / (c.radius_px * c.radius_px);
      t.depth = p.weight_spatial / radius_m2;
    }
    return t;
  }

  // Projected radius of a cluster in pixels: R f / z for DASP, R_rho (def. 5) from the mean
  // density otherwise.
  static float radiusPx(const Dalic& self, float depth, float mean_density) {
    const PixelFeatures& f = self.features_;
    if (self.params_.metric == MetricKind::kDepthAdaptive && depth > 0.0f) {
      return self.params_.radius_m * 0.5f * (f.intrinsics.fx + f.intrinsics.fy) / depth;
    }
    return mean_density > 0.0f ? 1.0f / std::sqrt(kPi * mean_density) : 1.0f;
  }
};

Dalic::Dalic(const PixelFeatures& features, const cv::Mat& density, const DalicParams& params)
    : features_(features), density_(density), params_(params) {
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
  if (!(params.window_multiple > 0.0f)) {
    throw std::invalid_argument("DALIC: window_multiple must be positive");
  }
  if (params.threads < 0) throw std::invalid_argument("DALIC: threads must be >= 0");
  params_ = params;
  clusters_.clear();
  if (labels_.size() != features.size()) {
    labels_.assign(features.size(), -1);
    distance_.assign(features.size(), kUnreached);
  }
}

Dalic::~Dalic() = default;

cv::Mat Dalic::labels() const {
  return cv::Mat(features_.height, features_.width, CV_32SC1, const_cast<int*>(labels_.data()));
}

void Dalic::initialize(const std::vector<Seed>& seeds) {
  const PixelFeatures& f = features_;
  const float* density = density_.ptr<float>();
  clusters_.clear();
  clusters_.reserve(seeds.size());
  for (std::size_t seed_index = 0; seed_index < seeds.size(); ++seed_index) {
    const Seed& seed = seeds[seed_index];
    const int cx = std::clamp(static_cast<int>(std::lround(seed.u)), 0, f.width - 1);
    const int cy = std::clamp(static_cast<int>(std::lround(seed.v)), 0, f.height - 1);
    const float seed_density = density[static_cast<std::size_t>(cy) * f.width + cx];
    const float nominal =
        seed_density > 0.0f ? 1.0f / std::sqrt(kPi * seed_density) : 3.0f;  // R_rho, pixels
    const int reach = std::clamp(static_cast<int>(std::lround(0.3f * nominal)), 1, 4);
    Cluster c;
    c.u = static_cast<float>(cx);
    c.v = static_cast<float>(cy);
    c.color.setZero();
    c.position.setZero();
    Eigen::Vector3f normal_sum = Eigen::Vector3f::Zero();
    int count = 0;
    for (int y = std::max(0, cy - reach); y <= std::min(f.height - 1, cy + reach); ++y) {
      for (int x = std::max(0, cx - reach); x <= std::min(f.width - 1, cx + reach); ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * f.width + x;
        if (!f.valid[i]) continue;
        ++count;
        c.color += Eigen::Vector3f(f.r[i], f.g[i], f.b[i]);
        if (f.hasDepth()) {
          c.position += Eigen::Vector3f(f.x[i], f.y[i], f.z[i]);
          normal_sum += Eigen::Vector3f(f.nx[i], f.ny[i], f.nz[i]);
        }
      }
    }
    if (count == 0) continue;  // seed without any valid pixel nearby: drop it
    c.color /= static_cast<float>(count);
    c.position /= static_cast<float>(count);
    c.normal = normal_sum.norm() > 0.0f ? Eigen::Vector3f(normal_sum.normalized())
                                        : Eigen::Vector3f(-Eigen::Vector3f::UnitZ());
    c.radius_px = Impl::radiusPx(*this, c.position.z(), seed_density);
    c.mass = 1.0f;
    c.origin = static_cast<int>(seed_index);
    clusters_.push_back(c);
  }
}

void Dalic::assign() {
  const PixelFeatures& f = features_;
  const std::size_t n = f.size();
  for (std::size_t i = 0; i < n; ++i) {
    distance_[i] = f.valid[i] ? kUnreached : kInvalidPixel;
    labels_[i] = -1;
  }
  std::vector<ClusterTerms> terms;
  terms.reserve(clusters_.size());
  for (const Cluster& c : clusters_) terms.push_back(Impl::terms(*this, c));
  detail::forChunks(f.height, kChunks, params_.threads, [&](int, int row_begin, int row_end) {
    switch (params_.metric) {
      case MetricKind::kDepthAdaptive:
        Impl::assignRows<MetricKind::kDepthAdaptive>(*this, terms, row_begin, row_end);
        break;
      case MetricKind::kColor2D:
        Impl::assignRows<MetricKind::kColor2D>(*this, terms, row_begin, row_end);
        break;
      case MetricKind::kColorDepth2D:
        Impl::assignRows<MetricKind::kColorDepth2D>(*this, terms, row_begin, row_end);
        break;
    }
  });
}

void Dalic::update() {
  const PixelFeatures& f = features_;
  const std::size_t k_count = clusters_.size();
  if (k_count == 0) return;
  const bool depth = f.hasDepth();
  const std::size_t stride = static_cast<std::size_t>(kAccSize) * k_count;
  accumulators_.assign(stride * kUpdateChunks, 0.0f);
  const float* density = density_.ptr<float>();
  detail::forChunks(
      f.height, kUpdateChunks, params_.threads, [&](int chunk, int row_begin, int row_end) {
        float* acc_base = accumulators_.data() + stride * static_cast<std::size_t>(chunk);
        // Labels come in horizontal runs: sum each run in registers, then add it once.
        for (int row = row_begin; row < row_end; ++row) {
          const std::size_t base = static_cast<std::size_t>(row) * f.width;
          const int* row_labels = labels_.data() + base;
          int col = 0;
          while (col < f.width) {
            const int k = row_labels[col];
            int end = col + 1;
            while (end < f.width && row_labels[end] == k) ++end;
            if (k >= 0) {
              const Cluster& c = clusters_[static_cast<std::size_t>(k)];
              float* a = acc_base + static_cast<std::size_t>(k) * kAccSize;
              const float dv = static_cast<float>(row) - c.v;
              const float run = static_cast<float>(end - col);
              const float first = static_cast<float>(col) - c.u;
              // Sum of (first + j) and (first + j)^2 for j = 0 .. run - 1.
              const float su = run * first + 0.5f * run * (run - 1.0f);
              const float suu = run * first * first + first * run * (run - 1.0f) +
                                (run - 1.0f) * run * (2.0f * run - 1.0f) / 6.0f;
              a[kCount] += run;
              a[kSu] += su;
              a[kSv] += run * dv;
              a[kSuu] += suu;
              a[kSvv] += run * dv * dv;
              a[kSuv] += su * dv;
              float sr = 0, sg = 0, sb = 0, mass = 0;
              for (int x = col; x < end; ++x) {
                sr += f.r[base + x];
                sg += f.g[base + x];
                sb += f.b[base + x];
                mass += density[base + x];
              }
              a[kSr] += sr;
              a[kSg] += sg;
              a[kSb] += sb;
              a[kMass] += mass;
              if (depth) {
                const detail::PointMoments m = detail::sumPointMoments(
                    f.x.data() + base, f.y.data() + base, f.z.data() + base, col, end,
                    c.position.x(), c.position.y(), c.position.z());
                a[kSx] += m.sx;
                a[kSy] += m.sy;
                a[kSz] += m.sz;
                a[kSxx] += m.sxx;
                a[kSxy] += m.sxy;
                a[kSxz] += m.sxz;
                a[kSyy] += m.syy;
                a[kSyz] += m.syz;
                a[kSzz] += m.szz;
              }
            }
            col = end;
          }
        }
      });
  for (int chunk = 1; chunk < kUpdateChunks; ++chunk) {
    const float* src = accumulators_.data() + stride * static_cast<std::size_t>(chunk);
    for (std::size_t j = 0; j < stride; ++j) accumulators_[j] += src[j];
  }

  std::vector<Cluster> next;
  next.reserve(k_count + static_cast<std::size_t>(std::max(0, params_.target_count)));
  for (std::size_t k = 0; k < k_count; ++k) {
    const float* a = accumulators_.data() + k * kAccSize;
    const float n = a[kCount];
    if (n <= 0.0f || a[kMass] < params_.min_size_fraction) continue;  // purge
    Cluster c = clusters_[k];
    const float inv_n = 1.0f / n;
    const float mu = a[kSu] * inv_n, mv = a[kSv] * inv_n;
    c.u += mu;
    c.v += mv;
    c.color = Eigen::Vector3f(a[kSr], a[kSg], a[kSb]) * inv_n;
    c.pixel_count = static_cast<int>(n);
    c.mass = a[kMass];
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
    if (depth) {
      const Eigen::Vector3f mean(a[kSx] * inv_n, a[kSy] * inv_n, a[kSz] * inv_n);
      c.position += mean;
      if (n >= 4.0f) {
        Eigen::Matrix3f cov;
        cov << a[kSxx] * inv_n, a[kSxy] * inv_n, a[kSxz] * inv_n, a[kSxy] * inv_n, a[kSyy] * inv_n,
            a[kSyz] * inv_n, a[kSxz] * inv_n, a[kSyz] * inv_n, a[kSzz] * inv_n;
        cov -= mean * mean.transpose();
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> solver;
        solver.computeDirect(cov);
        c.normal = solver.eigenvectors().col(0);  // smallest eigenvalue: plane normal (eq. 3.22)
      }  // else: too few points for a plane fit, keep the previous normal
      if (!(c.normal.norm() > 0.0f) || !c.normal.allFinite()) c.normal = -Eigen::Vector3f::UnitZ();
      c.normal.normalize();
      if (c.normal.dot(c.position) > 0.0f) c.normal = -c.normal;  // towards the camera
    }
    c.radius_px = Impl::radiusPx(*this, c.position.z(), c.mass * inv_n);
    next.push_back(c);
  }

  // Count control: split the heaviest clusters or drop the lightest until the target is met.
  const int target = params_.target_count;
  if (target > 0 && !next.empty()) {
    const int have = static_cast<int>(next.size());
    if (have > target) {
      std::vector<std::size_t> order(next.size());
      for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
      std::stable_sort(order.begin(), order.end(),
                       [&](std::size_t a, std::size_t b) { return next[a].mass < next[b].mass; });
      std::vector<std::uint8_t> drop(next.size(), 0);
      for (int i = 0; i < have - target; ++i) drop[order[static_cast<std::size_t>(i)]] = 1;
      std::vector<Cluster> kept;
      kept.reserve(static_cast<std::size_t>(target));
      for (std::size_t i = 0; i < next.size(); ++i) {
        if (!drop[i]) kept.push_back(next[i]);
      }
      next.swap(kept);
    } else if (have < target) {
      // Max-heap on mass; ties broken by index for determinism.
      std::priority_queue<std::pair<float, int>> heap;
      for (int i = 0; i < have; ++i) heap.push({next[static_cast<std::size_t>(i)].mass, -i});
      for (int added = 0; added < target - have; ++added) {
        const int index = -heap.top().second;
        heap.pop();
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
        next.push_back(child);  // capacity reserved above: no reallocation
        heap.push({parent_mass, -index});
        heap.push({child.mass, -static_cast<int>(next.size() - 1)});
      }
    }
  }
  clusters_.swap(next);
}

}  // namespace dasp

// Density-Adaptive Local Iterative Clustering (thesis §2.4, alg. 3) with the metrics of ASP
// (def. 7) and DASP (eq. 3.19-3.21), plane-fit cluster normals (§3.2.3), purge of tiny clusters
// and count control.
#include "dasp/dalic.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "dasp/density.h"
#include "parallel.h"
#include "run_sums.h"
#include "simd.h"

#if DASP_AVX512_FUNCTIONS
#include <immintrin.h>
#endif

namespace dasp {
namespace {

using detail::FeatureRow;
using detail::featureRow;
using detail::kLanes;
#if DASP_VECTOR_EXTENSIONS
using detail::coverSpanAligned;
using detail::loadVec;
using detail::storeVec;
using detail::Vec8f;
using detail::Vec8i;
#endif

constexpr float kPi = 3.14159265358979f;
constexpr int kChunks = 16;  // fixed row stripes of the assignment
// Fixed row stripes of the update, each with its own accumulators (same reductions for any
// thread count); few, because zeroing and summing them costs K * stripes.
constexpr int kUpdateChunks = 2;
constexpr float kUnreached = 1e30f;
// A cluster's points define a plane if their second principal variance is at least this
// fraction of the first (a strip 2 by 10 pixels gives 0.25 / 8.25 = 0.03).
constexpr float kMinPlaneSpread = 0.01f;
constexpr int kNormalSteps = 4;  // power-iteration steps of the plane normal
constexpr int kSpanBlock = 32;   // rows whose reach-disc chords are computed together
// Distance of pixels no cluster may take (the reduced distances of ClusterTerms can be < 0).
constexpr float kInvalidPixel = -std::numeric_limits<float>::max();

// Accumulators per cluster, sums relative to the cluster's previous centre: the pixel-position
// sums of the label runs (closed forms) and the feature sums of run_sums.h.
enum RunAcc : int { kCount, kSu, kSv, kSuu, kSvv, kSuv, kRunAccSize };
constexpr int kClusterAccSize = kRunAccSize + detail::kRunSums;  // floats per cluster

// Per-cluster constants of the distance, precomputed once per assign(). The distance is
// expanded, |f - f_i|^2 = |f|^2 - 2 f . f_i + |f_i|^2 for colour and (d_DA) 3D position, and
// the pixel's own |f|^2 terms are dropped: they are the same for every cluster the pixel is
// compared with, so the nearest cluster does not change. What remains is an affine function of
// the pixel's features, nine multiply-adds for d_DA (eq. 3.20). (With a depth exponent other
// than 2 every cluster has its own radius, |p|^2 / R_i^2 differs between clusters and stays.)
// The rounding error this adds is about 1e-7 |p|^2 / R^2 (1e-3 at 3 m with R = 2 cm) against
// distances of order 1: it decides only between clusters that are equally near. The 2D position of
// kColor2D / kColorDepth2D stays a difference (it is not a pixel feature).
struct ClusterTerms {
  int x0, x1, y0, y1;  // window, inclusive pixel bounds (never empty: it holds the centre)
  int id;              // cluster index, the label of the pixels it takes
  float u, v;
  float reach;          // radius of the disc the cluster can reach, pixels (C R + 1)
  float spatial;        // weight / R_rho^2 of the 2D compactness term (kColor2D, kColorDepth2D)
  float depth;          // weight / R^2 of the depth term (kColorDepth2D)
  float z;              // depth of the centre (kColorDepth2D)
  float cr, cg, cb;     // -2 wc c_i
  float cx, cy, cz;     // -2 (weight / R^2) p_i, z scaled by 1 + weight_depth (d_DA)
  float cnx, cny, cnz;  // -wn n_i (d_DA)
  float offset;         // wc |c_i|^2 (d_DA: + weight (|p_i|^2 + weight_depth z_i^2) / R^2 + wn)
  // d_DA with a per-cluster radius (depth_exponent != 2): the pixel's own (x^2 + y^2) and z^2
  // terms, weight / R_i^2 and that times 1 + weight_depth, which differ between clusters and
  // cannot be dropped. 0 otherwise.
  float cxy2, cz2;
};

// Whether d_DA gives every cluster its own radius (radiusAtDepth), which needs the cxy2 / cz2
// terms and the assignment loops that evaluate them.
bool perClusterRadius(const DalicParams& p) {
  return p.metric == MetricKind::kDepthAdaptive && p.depth_exponent != 2.0f;
}

// The (reduced, see ClusterTerms) distance of pixels to cluster t, for one pixel (float, int)
// or eight (Vec8f, Vec8i). dv2: squared row offset from the centre (2D metrics).
template <MetricKind kKind, bool kScaled, typename VecF, typename VecI, typename Load>
DASP_ALWAYS_INLINE VecF clusterDistance(const ClusterTerms& t, const Load& load, VecI col,
                                        float dv2) {
  VecF d = t.offset + t.cr * load(&FeatureRow::r) + t.cg * load(&FeatureRow::g) +
           t.cb * load(&FeatureRow::b);
  if constexpr (kKind == MetricKind::kDepthAdaptive) {
    d += t.cx * load(&FeatureRow::x) + t.cy * load(&FeatureRow::y) + t.cz * load(&FeatureRow::z) +
         t.cnx * load(&FeatureRow::nx) + t.cny * load(&FeatureRow::ny) +
         t.cnz * load(&FeatureRow::nz);
    if constexpr (kScaled) {
      const VecF x = load(&FeatureRow::x), y = load(&FeatureRow::y), z = load(&FeatureRow::z);
      d += t.cxy2 * (x * x + y * y) + t.cz2 * (z * z);
    }
  } else {
    VecF du;
    if constexpr (std::is_same_v<VecF, float>) {
      du = static_cast<float>(col) - t.u;
    } else {
      du = __builtin_convertvector(col, VecF) - t.u;
    }
    d += t.spatial * (du * du + dv2);
    if constexpr (kKind == MetricKind::kColorDepth2D) {
      const VecF dz = load(&FeatureRow::z) - t.z;
      d += t.depth * dz * dz;
    }
  }
  return d;
}

#if DASP_AVX512_FUNCTIONS
// The inner loop of assignRows for d_DA with AVX-512: spans [first, last) of one row, sixteen
// pixels at a time. A superpixel's chord in a row is 10 to 60 pixels long, so eight-lane vectors
// leave many lanes idle at the chord's ends and the loop costs per vector, not per pixel; with
// sixteen lanes the assignment of a 640x480 frame takes about a fifth less time. The vectors
// start at multiples of 16 columns (store forwarding, see coverSpanAligned); the loads and stores
// are masked to the span, so nothing outside the row is read or written, for any image width. As
// in the eight-lane loop, a pixel takes the cluster only if strictly nearer. The arrays must not
// alias (the feature rows are only read). kScaled: clusters have their own radius (cxy2, cz2).
template <bool kScaled>
DASP_AVX512_FUNCTION void assignSpansDepthAdaptive16(const FeatureRow& fr,
                                                     const ClusterTerms* terms, const int* spans,
                                                     int first, int last, float* __restrict d_row,
                                                     int* __restrict l_row) {
  const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  for (int s = first; s < last; ++s) {
    const int* span = spans + 3 * s;
    const int x0 = span[1], x1 = span[2];
    if (x0 > x1) continue;
    const ClusterTerms& t = terms[span[0]];
    const __m512 offset = _mm512_set1_ps(t.offset), cr = _mm512_set1_ps(t.cr),
                 cg = _mm512_set1_ps(t.cg), cb = _mm512_set1_ps(t.cb), cx = _mm512_set1_ps(t.cx),
                 cy = _mm512_set1_ps(t.cy), cz = _mm512_set1_ps(t.cz), cnx = _mm512_set1_ps(t.cnx),
                 cny = _mm512_set1_ps(t.cny), cnz = _mm512_set1_ps(t.cnz),
                 cxy2 = _mm512_set1_ps(t.cxy2), cz2 = _mm512_set1_ps(t.cz2);
    const __m512i id = _mm512_set1_epi32(t.id), first_col = _mm512_set1_epi32(x0),
                  last_col = _mm512_set1_epi32(x1);
    for (int c = x0 & ~15; c <= x1; c += 16) {
      const __m512i col = _mm512_add_epi32(_mm512_set1_epi32(c), lane);
      const __mmask16 in =
          _mm512_cmpge_epi32_mask(col, first_col) & _mm512_cmple_epi32_mask(col, last_col);
      // clusterDistance's d_DA, written out in two chains of multiply-adds (colour and normal,
      // position) that halve the latency: clusterDistance itself on __m512 made the assignment
      // 6 % slower. dalic_test checks both loops against the full metric.
      __m512 a = _mm512_fmadd_ps(cr, _mm512_maskz_loadu_ps(in, fr.r + c), offset);
      __m512 b = _mm512_mul_ps(cg, _mm512_maskz_loadu_ps(in, fr.g + c));
      a = _mm512_fmadd_ps(cb, _mm512_maskz_loadu_ps(in, fr.b + c), a);
      const __m512 px = _mm512_maskz_loadu_ps(in, fr.x + c),
                   py = _mm512_maskz_loadu_ps(in, fr.y + c),
                   pz = _mm512_maskz_loadu_ps(in, fr.z + c);
      b = _mm512_fmadd_ps(cx, px, b);
      a = _mm512_fmadd_ps(cnx, _mm512_maskz_loadu_ps(in, fr.nx + c), a);
      b = _mm512_fmadd_ps(cy, py, b);
      a = _mm512_fmadd_ps(cny, _mm512_maskz_loadu_ps(in, fr.ny + c), a);
      b = _mm512_fmadd_ps(cz, pz, b);
      a = _mm512_fmadd_ps(cnz, _mm512_maskz_loadu_ps(in, fr.nz + c), a);
      if constexpr (kScaled) {
        a = _mm512_fmadd_ps(cxy2, _mm512_fmadd_ps(px, px, _mm512_mul_ps(py, py)), a);
        b = _mm512_fmadd_ps(cz2, _mm512_mul_ps(pz, pz), b);
      }
      const __m512 d = _mm512_add_ps(a, b);
      const __mmask16 closer =
          _mm512_mask_cmp_ps_mask(in, d, _mm512_maskz_loadu_ps(in, d_row + c), _CMP_LT_OQ);
      _mm512_mask_storeu_ps(d_row + c, closer, d);
      _mm512_mask_storeu_epi32(l_row + c, closer, id);
    }
  }
}
#endif

// The assignment of rows [row_begin, row_end): each pixel to the nearest cluster whose reach
// disc holds it. Row by row, every cluster whose window meets the row in turn, in cluster order
// (the order in which alg. 3's cluster-by-cluster loop visits a pixel, so ties go the same
// way): the row's features stay in the L1 cache for the three or so clusters that reach each
// pixel, where a cluster-by-cluster loop would fetch them from L2 each time.
// clusters: the indices into terms of the clusters whose window meets the rows, ascending.
template <MetricKind kKind, bool kScaled = false>
DASP_ALWAYS_INLINE void assignRows(const PixelFeatures& f, const ClusterTerms* terms,
                                   const int* clusters, std::size_t count, int row_begin,
                                   int row_end, float* __restrict dist, int* __restrict label,
                                   std::vector<int>& scratch) {
  const int width = f.width;
  // The reach-disc spans of the clusters, bucketed by row (counting sort, in cluster order
  // within a row): the row loop below then visits only the clusters that reach the row.
  // scratch (kept across calls: no allocation or clearing per frame) holds the row starts, the
  // fill positions and the spans (cluster, x0, x1).
  const int rows = row_end - row_begin;
  const std::size_t needed = 2 * static_cast<std::size_t>(rows) + 2;
  if (scratch.size() < needed) scratch.resize(needed);
  // Clusters per row from a difference array, then the bucket starts.
  int* row_start = scratch.data();
  std::fill(row_start, row_start + rows + 2, 0);
  for (std::size_t i = 0; i < count; ++i) {
    const ClusterTerms& t = terms[clusters[i]];
    const int y0 = std::max(t.y0, row_begin), y1 = std::min(t.y1, row_end - 1);
    ++row_start[y0 - row_begin + 1];
    --row_start[y1 - row_begin + 2];
  }
  for (int i = 1; i <= rows; ++i) row_start[i] += row_start[i - 1];  // clusters of row i - 1
  for (int i = 1; i <= rows; ++i) row_start[i] += row_start[i - 1];  // starts
  const std::size_t total = static_cast<std::size_t>(row_start[rows]);
  if (scratch.size() < needed + 3 * total) scratch.resize(needed + 3 * total);
  row_start = scratch.data();
  int* fill = row_start + rows + 2;
  int* spans = fill + rows;
  std::copy(row_start, row_start + rows, fill);
  for (std::size_t i = 0; i < count; ++i) {
    const int k = clusters[i];
    const ClusterTerms& t = terms[k];
    const int y0 = std::max(t.y0, row_begin), y1 = std::min(t.y1, row_end - 1);
    const float u = t.u, v = t.v, reach2 = t.reach * t.reach;
    const float x0 = static_cast<float>(t.x0), x1 = static_cast<float>(t.x1);
    // Columns [x0, x1] of the cluster's reach disc in each row: only the chord of the disc;
    // pixels in the corners of the bounding square are farther than C R from the centre (alg. 3
    // tests the cluster's reach; the square is the thesis' simplification, 27 % more distance
    // evaluations). kSpanBlock rows at a time, in a loop the compiler vectorises (the bounds
    // are clamped to the window there, as floats: the store loop only copies). The loop always
    // computes all kSpanBlock rows, also those past the window that the store loop skips: with
    // the window's row count as its bound, its last rows (up to a vector's width) ran in scalar
    // code, and the assignment took 3-4 % longer at K = 1000-4000.
    for (int block = y0; block <= y1; block += kSpanBlock) {
      const int n = std::min(kSpanBlock, y1 - block + 1);
      int left[kSpanBlock] = {}, right[kSpanBlock] = {};  // all set below; zeroed for cppcheck
      for (int j = 0; j < kSpanBlock; ++j) {
        const float dv = static_cast<float>(block + j) - v;
        const float chord = std::sqrt(std::max(0.0f, reach2 - dv * dv));
        left[j] = static_cast<int>(std::max(x0, std::ceil(u - chord)));
        right[j] = static_cast<int>(std::min(x1, std::floor(u + chord)));
      }
      int* row_fill = fill + (block - row_begin);
      for (int j = 0; j < n; ++j) {
        int* span = spans + 3 * row_fill[j]++;
        span[0] = k;
        span[1] = left[j];
        span[2] = right[j];
      }
    }
  }
#if DASP_AVX512_FUNCTIONS
  const bool avx512 = kKind == MetricKind::kDepthAdaptive && detail::avx512Available();
#endif
  for (int row = row_begin; row < row_end; ++row) {
    const FeatureRow fr = featureRow(f, row);
    const std::size_t base = static_cast<std::size_t>(row) * width;
    float* __restrict d_row = dist + base;
    int* __restrict l_row = label + base;
    for (int col = 0; col < width; ++col) {
      d_row[col] = fr.valid[col] ? kUnreached : kInvalidPixel;
      l_row[col] = -1;
    }
#if DASP_AVX512_FUNCTIONS
    if (avx512) {
      assignSpansDepthAdaptive16<kScaled>(fr, terms, spans, row_start[row - row_begin],
                                          row_start[row - row_begin + 1], d_row, l_row);
      continue;
    }
#endif
    for (int s = row_start[row - row_begin]; s < row_start[row - row_begin + 1]; ++s) {
      const int* span = spans + 3 * s;
      const int x0 = span[1], x1 = span[2];
      if (x0 > x1) continue;
      const ClusterTerms t = terms[span[0]];  // a copy: the stores below cannot alias it
      const float dv = static_cast<float>(row) - t.v;
      const float dv2 = dv * dv;
#if DASP_VECTOR_EXTENSIONS
      {
        int start = 0, stop = 0;
        if (coverSpanAligned(x0, x1 + 1, width, start, stop)) {
          Vec8i col = start + Vec8i{0, 1, 2, 3, 4, 5, 6, 7};
          for (int c = start; c < stop; c += kLanes, col += kLanes) {
            const auto load = [&fr, c](const float* FeatureRow::*field) DASP_LAMBDA_ALWAYS_INLINE {
              return loadVec<Vec8f>(fr.*field + c);
            };
            const Vec8f d = clusterDistance<kKind, kScaled, Vec8f>(t, load, col, dv2);
            const Vec8f old = loadVec<Vec8f>(d_row + c);
            const Vec8i closer = (d < old) & (col >= x0) & (col <= x1);
            storeVec(d_row + c, closer ? d : old);
            storeVec(l_row + c, closer ? t.id + Vec8i{} : loadVec<Vec8i>(l_row + c));
          }
          continue;
        }
      }
#endif
      for (int col = x0; col <= x1; ++col) {
        const auto load = [&fr, col](const float* FeatureRow::*field)
                              DASP_LAMBDA_ALWAYS_INLINE { return (fr.*field)[col]; };
        const float d = clusterDistance<kKind, kScaled, float>(t, load, col, dv2);
        if (d < d_row[col]) {
          d_row[col] = d;
          l_row[col] = t.id;
        }
      }
    }
  }
}

DASP_VECTOR_CLONES void assignRowsDepthAdaptive(const PixelFeatures& f, const ClusterTerms* terms,
                                                const int* clusters, std::size_t count,
                                                int row_begin, int row_end, float* dist, int* label,
                                                std::vector<int>& scratch) {
  assignRows<MetricKind::kDepthAdaptive>(f, terms, clusters, count, row_begin, row_end, dist, label,
                                         scratch);
}

DASP_VECTOR_CLONES void assignRowsDepthAdaptiveScaled(const PixelFeatures& f,
                                                      const ClusterTerms* terms,
                                                      const int* clusters, std::size_t count,
                                                      int row_begin, int row_end, float* dist,
                                                      int* label, std::vector<int>& scratch) {
  assignRows<MetricKind::kDepthAdaptive, true>(f, terms, clusters, count, row_begin, row_end, dist,
                                               label, scratch);
}

DASP_VECTOR_CLONES void assignRowsColor2D(const PixelFeatures& f, const ClusterTerms* terms,
                                          const int* clusters, std::size_t count, int row_begin,
                                          int row_end, float* dist, int* label,
                                          std::vector<int>& scratch) {
  assignRows<MetricKind::kColor2D>(f, terms, clusters, count, row_begin, row_end, dist, label,
                                   scratch);
}

DASP_VECTOR_CLONES void assignRowsColorDepth2D(const PixelFeatures& f, const ClusterTerms* terms,
                                               const int* clusters, std::size_t count,
                                               int row_begin, int row_end, float* dist, int* label,
                                               std::vector<int>& scratch) {
  assignRows<MetricKind::kColorDepth2D>(f, terms, clusters, count, row_begin, row_end, dist, label,
                                        scratch);
}

// The update sums of rows [row_begin, row_end) into acc (kClusterAccSize floats per cluster).
// Labels come in horizontal runs: the pixel-position sums of a run have closed forms, the
// feature sums are summed along the run.
template <bool kDepth>
DASP_ALWAYS_INLINE void accumulateRows(const PixelFeatures& f, const float* density,
                                       const int* labels, const Cluster* clusters, int row_begin,
                                       int row_end, float* __restrict acc) {
  const int width = f.width;
  for (int row = row_begin; row < row_end; ++row) {
    const std::size_t base = static_cast<std::size_t>(row) * width;
    const FeatureRow fr = featureRow(f, row);
    const int* row_labels = labels + base;
    int col = 0;
    while (col < width) {
      const int k = row_labels[col];
      const int end = detail::labelRunEnd(row_labels, col, width);
      if (k >= 0) {
        const Cluster& c = clusters[k];
        float* a = acc + static_cast<std::size_t>(k) * kClusterAccSize;
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
        detail::addRunSums<true, kDepth, false>(fr, density + base, width, col, end, c.position.x(),
                                                c.position.y(), c.position.z(), a + kRunAccSize);
      }
      col = end;
    }
  }
}

DASP_VECTOR_CLONES void accumulateRowsDepth(const PixelFeatures& f, const float* density,
                                            const int* labels, const Cluster* clusters,
                                            int row_begin, int row_end, float* acc) {
  accumulateRows<true>(f, density, labels, clusters, row_begin, row_end, acc);
}

DASP_VECTOR_CLONES void accumulateRowsColor(const PixelFeatures& f, const float* density,
                                            const int* labels, const Cluster* clusters,
                                            int row_begin, int row_end, float* acc) {
  accumulateRows<false>(f, density, labels, clusters, row_begin, row_end, acc);
}

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

#pragma once

// The per-pixel loops of DALIC: the assignment of the pixels to the nearest cluster whose reach
// disc holds them (eight lanes, or sixteen with AVX-512 for d_DA) and the update sums of the
// clusters' pixels over label runs, each built for several instruction sets (DASP_VECTOR_CLONES).
// Included by dalic.cpp alone, after its other headers: one translation unit, as when this was
// part of dalic.cpp. GCC's code for DALIC depends on the whole unit, down to the order of the
// declarations, and under -fassociative-math that reaches the results: compiled as an object of
// its own, Dalic::assign() computed some distance constants differently in the last bit and one
// label of the 45 OSD learn frames changed. Hence internal linkage, as in one file.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

#include "dasp/dalic.h"
#include "dasp/features.h"
#include "run_sums.h"
#include "simd.h"

#if DASP_AVX512_FUNCTIONS
#include <immintrin.h>
#endif

namespace dasp {
namespace {  // internal linkage in dalic.cpp's unit, see above

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

constexpr float kUnreached = 1e30f;
constexpr int kSpanBlock = 32;  // rows whose reach-disc chords are computed together
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

}  // namespace
}  // namespace dasp

// Feature sums along runs of pixels of one label in one image row: the inner loop of the DALIC
// update and of the superpoint fit (internal to the dasp library).
#pragma once

#include <cstdint>

#include "dasp/features.h"
#include "point_moments.h"
#include "simd.h"

namespace dasp::detail {

/// The features of one image row (x .. nz are null without depth).
struct FeatureRow {
  const float *r, *g, *b, *x, *y, *z, *nx, *ny, *nz;
  const std::uint8_t* valid;
};

DASP_ALWAYS_INLINE FeatureRow featureRow(const PixelFeatures& f, int row) {
  const std::size_t base = static_cast<std::size_t>(row) * f.width;
  const bool depth = f.hasDepth();
  return {f.r.data() + base,
          f.g.data() + base,
          f.b.data() + base,
          depth ? f.x.data() + base : nullptr,
          depth ? f.y.data() + base : nullptr,
          depth ? f.z.data() + base : nullptr,
          depth ? f.nx.data() + base : nullptr,
          depth ? f.ny.data() + base : nullptr,
          depth ? f.nz.data() + base : nullptr,
          f.valid.data() + base};
}

/// The sums of a run, in this order: colour, density, the 3D point moments of addPointMoments
/// (relative to a reference point), the normal. Exactly two vectors of kLanes floats.
enum RunSum : int {
  kSumR,
  kSumG,
  kSumB,
  kSumDensity,
  kSumX,  // the nine point moments start here
  kSumNx = kSumX + 9,
  kSumNy,
  kSumNz,
  kRunSums
};
static_assert(kRunSums == 2 * kLanes, "the run sums fill two vectors");

#if DASP_VECTOR_EXTENSIONS
/// Lane-wise sums of pairs: (a0 + a1, a2 + a3, b0 + b1, b2 + b3, a4 + a5, a6 + a7, b4 + b5,
/// b6 + b7) (one vhaddps on AVX).
DASP_ALWAYS_INLINE Vec8f pairSums(const Vec8f& a, const Vec8f& b) {
  return __builtin_shuffle(a, b, Vec8i{0, 2, 8, 10, 4, 6, 12, 14}) +
         __builtin_shuffle(a, b, Vec8i{1, 3, 9, 11, 5, 7, 13, 15});
}

/// The lane totals of eight vectors: (sum of v[0], ..., sum of v[7]).
DASP_ALWAYS_INLINE Vec8f laneTotals(const Vec8f* v) {
  const Vec8f low = pairSums(pairSums(v[0], v[1]), pairSums(v[2], v[3]));   // v0..v3, halves
  const Vec8f high = pairSums(pairSums(v[4], v[5]), pairSums(v[6], v[7]));  // v4..v7, halves
  return __builtin_shuffle(low, high, Vec8i{0, 1, 2, 3, 8, 9, 10, 11}) +
         __builtin_shuffle(low, high, Vec8i{4, 5, 6, 7, 12, 13, 14, 15});
}
#endif

/// Adds the sums (RunSum order) of the pixels [begin, end) of one row of `width` pixels to
/// sums[0 .. kRunSums). density: the row's density (kDensity); points relative to (rx, ry, rz)
/// (kDepth); normals (kNormals, needs kDepth). The pixels are summed in vector lanes, masked to
/// the run, and the lanes added up once at the end of the run.
template <bool kDensity, bool kDepth, bool kNormals>
DASP_ALWAYS_INLINE void addRunSums(const FeatureRow& fr, const float* density, int width, int begin,
                                   int end, float rx, float ry, float rz, float* __restrict sums) {
  static_assert(kDepth || !kNormals, "normals need depth");
#if DASP_VECTOR_EXTENSIONS
  int start = 0, stop = 0;
  if (coverSpan(begin, end, width, start, stop)) {
    Vec8f sum[kRunSums] = {};
    Vec8i col = start + Vec8i{0, 1, 2, 3, 4, 5, 6, 7};
    const Vec8f zero{};
    for (int c = start; c < stop; c += kLanes, col += kLanes) {
      const Vec8i in = (col >= begin) & (col < end);
      sum[kSumR] += in ? loadVec<Vec8f>(fr.r + c) : zero;
      sum[kSumG] += in ? loadVec<Vec8f>(fr.g + c) : zero;
      sum[kSumB] += in ? loadVec<Vec8f>(fr.b + c) : zero;
      if constexpr (kDensity) sum[kSumDensity] += in ? loadVec<Vec8f>(density + c) : zero;
      if constexpr (kDepth) {
        const Vec8f dx = in ? loadVec<Vec8f>(fr.x + c) - rx : zero;
        const Vec8f dy = in ? loadVec<Vec8f>(fr.y + c) - ry : zero;
        const Vec8f dz = in ? loadVec<Vec8f>(fr.z + c) - rz : zero;
        addPointMoments(sum + kSumX, dx, dy, dz);
      }
      if constexpr (kNormals) {
        sum[kSumNx] += in ? loadVec<Vec8f>(fr.nx + c) : zero;
        sum[kSumNy] += in ? loadVec<Vec8f>(fr.ny + c) : zero;
        sum[kSumNz] += in ? loadVec<Vec8f>(fr.nz + c) : zero;
      }
    }
    storeVec(sums, loadVec<Vec8f>(sums) + laneTotals(sum));
    if constexpr (kDepth) {
      storeVec(sums + kLanes, loadVec<Vec8f>(sums + kLanes) + laneTotals(sum + kLanes));
    }
    return;
  }
#endif
  for (int col = begin; col < end; ++col) {
    sums[kSumR] += fr.r[col];
    sums[kSumG] += fr.g[col];
    sums[kSumB] += fr.b[col];
    if constexpr (kDensity) sums[kSumDensity] += density[col];
    if constexpr (kDepth) {
      addPointMoments(sums + kSumX, fr.x[col] - rx, fr.y[col] - ry, fr.z[col] - rz);
    }
    if constexpr (kNormals) {
      sums[kSumNx] += fr.nx[col];
      sums[kSumNy] += fr.ny[col];
      sums[kSumNz] += fr.nz[col];
    }
  }
}

}  // namespace dasp::detail

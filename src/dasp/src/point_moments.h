// First and second moments of 3D points, summed along a run of pixels: the inner loop of the
// DALIC update and of the superpoint fit (internal to the dasp library).
#pragma once

namespace dasp::detail {

/// Sums of d = p - reference and of the products d_i d_j (metres, camera optical frame).
struct PointMoments {
  float sx = 0, sy = 0, sz = 0;
  float sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
};

/// Moments of the points (x[i], y[i], z[i]) for i in [begin, end), relative to (rx, ry, rz) so that
/// float sums stay precise.
inline PointMoments sumPointMoments(const float* x, const float* y, const float* z, int begin,
                                    int end, float rx, float ry, float rz) {
  PointMoments m;
  for (int i = begin; i < end; ++i) {
    const float dx = x[i] - rx, dy = y[i] - ry, dz = z[i] - rz;
    m.sx += dx;
    m.sy += dy;
    m.sz += dz;
    m.sxx += dx * dx;
    m.sxy += dx * dy;
    m.sxz += dx * dz;
    m.syy += dy * dy;
    m.syz += dy * dz;
    m.szz += dz * dz;
  }
  return m;
}

}  // namespace dasp::detail

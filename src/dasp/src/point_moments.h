// First and second moments of 3D points, summed along runs of pixels: the inner loops of the
// DALIC update and of the superpoint fit (internal to the dasp library).
#pragma once

#include "simd.h"

namespace dasp::detail {

/// Adds the moments of the offsets (dx, dy, dz) of points from a reference point (metres, camera
/// optical frame) to s[0..8]: the sums of dx, dy, dz, dx dx, dx dy, dx dz, dy dy, dy dz, dz dz.
/// T is float or a vector of floats (lane-wise sums).
template <typename T>
DASP_ALWAYS_INLINE void addPointMoments(T* s, const T& dx, const T& dy, const T& dz) {
  s[0] += dx;
  s[1] += dy;
  s[2] += dz;
  s[3] += dx * dx;
  s[4] += dx * dy;
  s[5] += dx * dz;
  s[6] += dy * dy;
  s[7] += dy * dz;
  s[8] += dz * dz;
}

}  // namespace dasp::detail

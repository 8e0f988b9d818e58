// The density's depth exponent a (DaspExperimental::depth_exponent) as a count of square roots,
// shared by the input check and the density.
#pragma once

#include <cmath>
#include <stdexcept>

namespace dasp::detail {

// a as the number k = 2 (2 - a) of factors 1 / sqrt(z) in z^(a - 2) (validated: a in [0, 2] and
// a multiple of 0.5, so that no per-pixel pow is needed).
inline int inverseRootFactors(float depth_exponent) {
  const float k = 2.0f * (2.0f - depth_exponent);
  if (!(k >= 0.0f && k <= 4.0f) || k != std::round(k)) {
    throw std::invalid_argument("DASP: depth_exponent must be one of 0, 0.5, 1, 1.5, 2");
  }
  return static_cast<int>(k);
}

}  // namespace dasp::detail

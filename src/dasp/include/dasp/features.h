// Stage 1 of DASP (alg. 4, thesis §3.2.1): input checks and the per-pixel features (colour, 3D
// points, normals, 3D area). Conventions: dasp/dasp.h.
#pragma once

#include <cstdint>

#include <opencv2/core.hpp>

#include "dasp/dasp.h"
#include "dasp/pixel_allocator.h"

namespace dasp {

/// Per-pixel features in structure-of-arrays layout (index = row * width + column).
/// Colour-only features (computeColorFeatures) leave the 3D arrays empty.
struct PixelFeatures {
  int width = 0;
  int height = 0;
  Intrinsics intrinsics;
  PixelVector<float> r, g, b;     ///< Colour in [0, 1].
  PixelVector<float> x, y, z;     ///< 3D point (eq. 3.4), metres, optical frame; 0 if invalid.
  PixelVector<float> nx, ny, nz;  ///< Unit normal towards the camera (eq. 3.8, 3.9); 0 if invalid.
  /// 3D surface area seen by the pixel, m^2: (z^2 / (fx fy)) times the slant factor, the
  /// perspective form of sqrt(|grad D|^2 + 1) in eq. 3.14/3.15, clamped to
  /// DaspExperimental::max_slant_factor.
  PixelVector<float> area;
  PixelVector<std::uint8_t> valid;  ///< 1 where depth (or, colour only, the pixel) is usable.
  int valid_count = 0;

  bool hasDepth() const { return !z.empty(); }
  std::size_t size() const { return static_cast<std::size_t>(width) * height; }
};

/// Checks a frame and the DASP parameters; throws std::invalid_argument with the reason.
/// Does not look at the depth values (computeFeatures reports "no valid depth").
void validateInput(const RgbdFrame& frame, const DaspConfig& config);

/// Stage 1 of alg. 4: colour, 3D points and normals from robust finite differences of depth
/// (eq. 3.4, 3.6-3.10) and the per-pixel 3D area for the density. Throws if no pixel has depth.
PixelFeatures computeFeatures(const RgbdFrame& frame, const DaspConfig& config = {});
/// The same into `features`, reusing its storage: a stream of same-sized frames allocates nothing.
void computeFeatures(const RgbdFrame& frame, const DaspConfig& config, PixelFeatures& features);

/// Colour-only features of a CV_8UC3 BGR image; every pixel valid.
PixelFeatures computeColorFeatures(const cv::Mat& color);

}  // namespace dasp

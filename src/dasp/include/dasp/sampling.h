// Seeding of superpixel centres from a density (thesis §2.3): Simplified Poisson Disc Sampling
// (alg. 1, 2), white noise and a regular grid.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "dasp/dasp.h"

namespace dasp {

/// A sampled superpixel centre in pixel coordinates.
struct Seed {
  float u = 0.0f;
  float v = 0.0f;
};

/// Density pyramid of eq. 2.7: level 0 is the density, level l+1 sums 2x2 blocks of level l
/// (images whose size is not a power of two are padded with zero density). The last level is
/// 1x1 and holds the integral.
class DensityPyramid {
 public:
  explicit DensityPyramid(const cv::Mat& density);
  int levels() const { return static_cast<int>(level_.size()); }
  const cv::Mat& level(int l) const { return level_[static_cast<std::size_t>(l)]; }  ///< CV_64F
  /// Mass of node (x, y) at level l; 0 outside the level.
  double mass(int l, int x, int y) const;

 private:
  std::vector<cv::Mat> level_;
};

/// Simplified Poisson Disc Sampling: alg. 1 (improved = false) or alg. 2 (improved = true).
/// density: CV_32FC1, >= 0, superpixels per pixel.
std::vector<Seed> sampleSpds(const cv::Mat& density, bool improved, std::uint64_t seed);
/// White-noise sampling: round(integral) independent draws with probability proportional to rho.
std::vector<Seed> sampleRandom(const cv::Mat& density, std::uint64_t seed);
/// Regular grid with spacing 1 / sqrt(mean positive density), points on positive density only.
std::vector<Seed> sampleGrid(const cv::Mat& density);
/// Dispatches on the method.
std::vector<Seed> sampleSeeds(const cv::Mat& density, SeedingMethod method, std::uint64_t seed);

}  // namespace dasp

// Densities of Adaptive and Depth-Adaptive Superpixels (thesis §2.2, §3.2.2): the depth-adaptive
// density (eq. 3.15), the constant density of the baselines and the superpixel radius for a count.
#pragma once

#include <opencv2/core.hpp>

#include "dasp/dasp.h"
#include "dasp/features.h"

namespace dasp {

/// Superpixel radius R (metres) for which the depth-adaptive density integrates to `count`
/// over the valid pixels (eq. 3.17): R = sqrt(sum area (z / 1 m)^(a - 2) / (pi count)), a the
/// depth exponent (DaspExperimental::depth_exponent; 2: the thesis, R = sqrt(sum area / (pi
/// count))).
float radiusForCount(const PixelFeatures& features, int count, float depth_exponent = 2.0f);

/// The 3D superpixel radius at depth z for the radius R at 1 m and the depth exponent a:
/// R (z / 1 m)^((2 - a) / 2); R itself for a = 2 (every depth) or z <= 0.
float radiusAtDepth(float radius_m, float depth_m, float depth_exponent);

/// Depth-adaptive density (eq. 3.15): rho(u) = area(u) (z / 1 m)^(a - 2) / (pi R^2)
/// superpixels per pixel (a = 2: area / (pi R^2)), 0 where depth is invalid. CV_32FC1.
/// depth_exponent: one of 0, 0.5, 1, 1.5, 2 (else std::invalid_argument).
cv::Mat computeDepthDensity(const PixelFeatures& features, float radius_m,
                            float depth_exponent = 2.0f);
/// The same into `density`, reusing its storage when the size matches.
void computeDepthDensity(const PixelFeatures& features, float radius_m, cv::Mat& density,
                         float depth_exponent = 2.0f);

/// Constant density over the valid pixels that integrates to `count`. CV_32FC1.
cv::Mat computeConstantDensity(const PixelFeatures& features, int count);

/// Sum of all density values (the expected number of superpixels).
double densityIntegral(const cv::Mat& density);

/// The radius R (metres, at 1 m for depth exponents other than 2) DASP uses for `config`:
/// radiusForCount(features, superpixel_count, depth_exponent) in count mode, radius_m in radius
/// mode.
float daspRadius(const PixelFeatures& features, const DaspConfig& config);

}  // namespace dasp

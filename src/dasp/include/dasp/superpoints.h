// The superpoint fit (thesis §3.2.3): per superpixel label the mean features, plane-fit normal
// and eigenvalue shape properties.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "dasp/dasp.h"
#include "dasp/features.h"

namespace dasp {

/// Superpoint fit: per label the mean colour, position and pixel position, plane-fit normal and
/// eigenvalue shape properties (§3.2.3). labels CV_32SC1 with values -1..n-1.
/// radius_m and depth_exponent give each superpixel's Superpixel::radius_m (radiusAtDepth).
std::vector<Superpixel> fitSuperpoints(const cv::Mat& labels, const PixelFeatures& features,
                                       const cv::Mat& density, float radius_m,
                                       float depth_exponent = 2.0f);

}  // namespace dasp

// Connectivity enforcement: every superpixel label made 4-connected, in the image or on the
// surface. Not in the thesis; rules in full: docs/dasp_core.md#connectivity-enforcement
#pragma once

#include <opencv2/core.hpp>

#include "dasp/dasp.h"

namespace dasp {

/// Makes every label 4-connected, on the surface if depth is given (no connection across a depth
/// jump of more than depth_jump_ratio times the nearer depth): pieces lighter than min_weight and
/// unlabelled valid pixels join the label they share the longest border with, or become -1. Labels
/// renumbered 0..n-1; returns n. valid: CV_8UC1 or empty (all valid); weight: CV_32FC1 (e.g. the
/// density) or empty (pixel count); depth: CV_32FC1 metres (0 = invalid) or empty.
int enforceConnectivity(cv::Mat& labels, const cv::Mat& valid, const cv::Mat& weight,
                        double min_weight, const cv::Mat& depth = cv::Mat(),
                        float depth_jump_ratio = DaspConfig{}.depth_jump_ratio);

}  // namespace dasp

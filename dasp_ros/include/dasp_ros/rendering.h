#pragma once
// Pictures of segmentations for the lazy image outputs (all CV_8UC3 BGR unless stated).

#include <dasp/dasp.h>

#include <opencv2/core.hpp>
#include <vector>

namespace dasp_ros {

/// Superpixel boundaries (red) over the colour image; pixels without a label darkened to a
/// third (what dasp_segment --overlay writes).
cv::Mat drawBoundaryOverlay(const cv::Mat& bgr, const cv::Mat& labels);

/// Every pixel in its superpixel's mean colour, segment boundaries red, unlabelled pixels black.
/// segment_labels: pixel segment labels (CV_32SC1, -1 = none).
cv::Mat drawSegmentOverlay(const cv::Mat& superpixel_labels,
                           const std::vector<dasp::Superpixel>& superpixels,
                           const cv::Mat& segment_labels);

/// Ultrametric contour map as mono8: 255 (1 - sqrt(min(level, 1))) on boundaries, 255 elsewhere
/// (dark strokes on white, as dasp_sdasp draws it).
cv::Mat ucmToMono8(const cv::Mat& ucm);

/// Deterministic false colour of a label (stable for the same label over frames).
cv::Vec3b labelColor(long long label);

}  // namespace dasp_ros

// Temporal label consistency of a video segmentation with known depth and camera motion: the
// share of valid pixels whose segment label in frame t is found again at the same surface point
// in frame t+1 (thesis ch. 5 evaluation; the motion compensation uses the depth of frame t and
// the relative camera pose).
#pragma once

#include <cstddef>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "dasp/dasp.h"

namespace dasp {
namespace metrics {

/// How the labels of the two frames are compared.
enum class LabelMatching {
  /// Labels are compared as they are (a method that keeps its labels over time).
  kIdentity,
  /// Every label of frame t is first mapped one-to-one to the label of frame t+1 it overlaps most
  /// after warping (greedy on the overlap counts, largest first; unmatched labels match nothing).
  /// This is the fair comparison for methods that segment every frame independently.
  kBestOverlap,
};

/// Result of temporalLabelConsistency.
struct TemporalConsistency {
  double consistency = 0.0;  ///< kept / compared (0 if nothing compared)
  std::size_t compared = 0;  ///< pixels of frame t that land on a valid pixel of frame t+1
  std::size_t kept = 0;      ///< of those, how many carry the same (matched) label
};

/// Warps every pixel of frame t with a label >= 0 and depth > 0 into frame t+1
/// (p_next = next_from_current * p_t, pinhole `intrinsics`), rounds to the nearest pixel and
/// compares labels where frame t+1 has a label >= 0 and a depth within `depth_tolerance`
/// (relative) of the warped point's depth, i.e. the same surface and not an occluder.
/// labels: CV_32SC1; depth: CV_16UC1 mm or CV_32FC1 m; all four of one size.
TemporalConsistency temporalLabelConsistency(const cv::Mat& labels_t, const cv::Mat& depth_t,
                                             const cv::Mat& labels_next, const cv::Mat& depth_next,
                                             const Intrinsics& intrinsics,
                                             const Eigen::Isometry3f& next_from_current,
                                             LabelMatching matching, float depth_tolerance = 0.03f);

}  // namespace metrics
}  // namespace dasp

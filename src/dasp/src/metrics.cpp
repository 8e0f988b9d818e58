// Metrics of a partition against a reference partition: boundary scores and curves,
// undersegmentation error and achievable segmentation accuracy (thesis appendix A). Those of a
// partition alone: metrics_intrinsic.cpp.
#include "dasp/metrics.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

#include "metrics_common.h"

namespace dasp {
namespace metrics {

using detail::checkLabels;
using detail::checkMask;
using detail::DenseLabels;
using detail::inMask;

namespace {

// Reference labels as CV_32SC1 (accepts 8-bit, 16-bit and 32-bit integer images).
cv::Mat referenceAsInt(const cv::Mat& ground_truth, const cv::Size& size, const char* what) {
  if (ground_truth.empty()) {
    throw std::invalid_argument(std::string(what) + ": ground truth is empty");
  }
  if (ground_truth.size() != size) {
    throw std::invalid_argument(std::string(what) +
                                ": ground truth size differs from the label image");
  }
  if (ground_truth.channels() != 1) {
    throw std::invalid_argument(std::string(what) + ": ground truth must have one channel");
  }
  switch (ground_truth.depth()) {
    case CV_32S:
      return ground_truth;
    case CV_8U:
    case CV_16U:
    case CV_16S:
    case CV_8S: {
      cv::Mat converted;
      ground_truth.convertTo(converted, CV_32S);
      return converted;
    }
    default:
      throw std::invalid_argument(std::string(what) + ": ground truth must be an integer image");
  }
}

// Contingency table between a partition and a reference over the mask.
struct Overlap {
  std::vector<std::size_t> segment_size;    // |S|
  std::vector<std::size_t> reference_size;  // |T|
  // For each segment the list of (reference index, |S n T|).
  std::vector<std::vector<std::pair<int, std::size_t>>> per_segment;
  std::size_t pixels = 0;
};

Overlap computeOverlap(const cv::Mat& labels, const cv::Mat& ground_truth, const cv::Mat& mask,
                       const char* what) {
  checkLabels(labels, what);
  checkMask(mask, labels.size(), what);
  const cv::Mat reference = referenceAsInt(ground_truth, labels.size(), what);
  const DenseLabels segments(labels, mask, true);
  const DenseLabels references(reference, mask, true);
  if (segments.pixels == 0) {
    throw std::invalid_argument(std::string(what) + ": mask has no valid pixel");
  }
  Overlap overlap;
  overlap.pixels = segments.pixels;
  overlap.segment_size.assign(segments.count, 0);
  overlap.reference_size.assign(references.count, 0);
  // Joint counts |S n T|: a dense table when it is small (superpixels x a few objects).
  const std::size_t cells =
      static_cast<std::size_t>(segments.count) * static_cast<std::size_t>(references.count);
  const bool dense = cells <= (std::size_t{1} << 25);
  std::vector<std::size_t> table(dense ? cells : 0, 0);
  std::unordered_map<std::uint64_t, std::size_t> joint;
  for (int y = 0; y < labels.rows; ++y) {
    const int* s_row = segments.index.ptr<int>(y);
    const int* t_row = references.index.ptr<int>(y);
    for (int x = 0; x < labels.cols; ++x) {
      const int s = s_row[x];
      if (s < 0) continue;
      const int t = t_row[x];
      ++overlap.segment_size[s];
      ++overlap.reference_size[t];
      if (dense) {
        ++table[static_cast<std::size_t>(s) * references.count + t];
      } else {
        ++joint[(static_cast<std::uint64_t>(s) << 32) | static_cast<std::uint32_t>(t)];
      }
    }
  }
  overlap.per_segment.resize(segments.count);
  if (dense) {
    for (int s = 0; s < segments.count; ++s) {
      for (int t = 0; t < references.count; ++t) {
        const std::size_t count = table[static_cast<std::size_t>(s) * references.count + t];
        if (count > 0) overlap.per_segment[s].emplace_back(t, count);
      }
    }
  } else {
    for (const auto& [key, count] : joint) {
      const int s = static_cast<int>(key >> 32);
      const int t = static_cast<int>(key & 0xffffffffu);
      overlap.per_segment[s].emplace_back(t, count);
    }
  }
  return overlap;
}

// Boundary map over the mask where unlabelled pixels (label < 0) form one segment.
cv::Mat boundaryMapImpl(const cv::Mat& labels, const cv::Mat& mask) {
  cv::Mat boundary(labels.size(), CV_8UC1, cv::Scalar(0));
  auto normalised = [](int label) { return label < 0 ? -1 : label; };
  for (int y = 0; y < labels.rows; ++y) {
    const int* row = labels.ptr<int>(y);
    std::uint8_t* out = boundary.ptr<std::uint8_t>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (!inMask(mask, y, x)) continue;
      const int label = normalised(row[x]);
      bool edge = false;
      if (x > 0 && inMask(mask, y, x - 1) && normalised(row[x - 1]) != label) edge = true;
      if (!edge && x + 1 < labels.cols && inMask(mask, y, x + 1) &&
          normalised(row[x + 1]) != label) {
        edge = true;
      }
      if (!edge && y > 0 && inMask(mask, y - 1, x) &&
          normalised(labels.at<int>(y - 1, x)) != label) {
        edge = true;
      }
      if (!edge && y + 1 < labels.rows && inMask(mask, y + 1, x) &&
          normalised(labels.at<int>(y + 1, x)) != label) {
        edge = true;
      }
      if (edge) out[x] = 255;
    }
  }
  return boundary;
}

cv::Mat dilateSquare(const cv::Mat& boundary, int tolerance_px) {
  if (tolerance_px == 0) return boundary;
  cv::Mat dilated;
  const cv::Mat kernel = cv::getStructuringElement(
      cv::MORPH_RECT, cv::Size(2 * tolerance_px + 1, 2 * tolerance_px + 1));
  cv::dilate(boundary, dilated, kernel);
  return dilated;
}

}  // namespace

cv::Mat boundaryMap(const cv::Mat& labels, const cv::Mat& mask) {
  checkLabels(labels, "boundaryMap");
  checkMask(mask, labels.size(), "boundaryMap");
  return boundaryMapImpl(labels, mask);
}

BoundaryScores boundaryScores(const cv::Mat& labels, const cv::Mat& ground_truth,
                              const cv::Mat& mask, int tolerance_px) {
  const char* what = "boundaryScores";
  checkLabels(labels, what);
  checkMask(mask, labels.size(), what);
  if (tolerance_px < 0) {
    throw std::invalid_argument("boundaryScores: tolerance_px must be >= 0");
  }
  const cv::Mat reference = referenceAsInt(ground_truth, labels.size(), what);
  if (!mask.empty() && cv::countNonZero(mask) == 0) {
    throw std::invalid_argument("boundaryScores: mask has no valid pixel");
  }
  const cv::Mat partition_boundary = boundaryMapImpl(labels, mask);
  const cv::Mat reference_boundary = boundaryMapImpl(reference, mask);
  const cv::Mat partition_near = dilateSquare(partition_boundary, tolerance_px);
  const cv::Mat reference_near = dilateSquare(reference_boundary, tolerance_px);

  BoundaryScores scores;
  scores.partition_boundary_pixels = static_cast<std::size_t>(cv::countNonZero(partition_boundary));
  scores.reference_boundary_pixels = static_cast<std::size_t>(cv::countNonZero(reference_boundary));
  cv::Mat matched;
  cv::bitwise_and(reference_boundary, partition_near, matched);
  const double recalled = cv::countNonZero(matched);
  cv::bitwise_and(partition_boundary, reference_near, matched);
  const double precise = cv::countNonZero(matched);
  scores.recall = scores.reference_boundary_pixels == 0
                      ? 1.0
                      : recalled / static_cast<double>(scores.reference_boundary_pixels);
  scores.precision = scores.partition_boundary_pixels == 0
                         ? 1.0
                         : precise / static_cast<double>(scores.partition_boundary_pixels);
  const double sum = scores.precision + scores.recall;
  scores.f1 = sum > 0.0 ? 2.0 * scores.precision * scores.recall / sum : 0.0;
  return scores;
}

double undersegmentationErrorThesis(const cv::Mat& labels, const cv::Mat& ground_truth,
                                    const cv::Mat& mask, double gamma) {
  if (!(gamma >= 0.0 && gamma <= 1.0)) {
    throw std::invalid_argument("undersegmentationErrorThesis: gamma must be in [0, 1]");
  }
  const Overlap overlap =
      computeOverlap(labels, ground_truth, mask, "undersegmentationErrorThesis");
  // Sum over T and S of |S| [|S n T| / |S| > gamma]; iterate per segment over its references.
  double covered = 0.0;
  for (std::size_t s = 0; s < overlap.per_segment.size(); ++s) {
    const double size = static_cast<double>(overlap.segment_size[s]);
    for (const auto& [t, count] : overlap.per_segment[s]) {
      (void)t;
      if (static_cast<double>(count) / size > gamma) covered += size;
    }
  }
  return covered / static_cast<double>(overlap.pixels) - 1.0;
}

double undersegmentationErrorNp(const cv::Mat& labels, const cv::Mat& ground_truth,
                                const cv::Mat& mask) {
  const Overlap overlap = computeOverlap(labels, ground_truth, mask, "undersegmentationErrorNp");
  double leak = 0.0;
  for (std::size_t s = 0; s < overlap.per_segment.size(); ++s) {
    const std::size_t size = overlap.segment_size[s];
    for (const auto& [t, count] : overlap.per_segment[s]) {
      (void)t;
      leak += static_cast<double>(std::min(count, size - count));
    }
  }
  return leak / static_cast<double>(overlap.pixels);
}

double achievableSegmentationAccuracy(const cv::Mat& labels, const cv::Mat& ground_truth,
                                      const cv::Mat& mask) {
  const Overlap overlap =
      computeOverlap(labels, ground_truth, mask, "achievableSegmentationAccuracy");
  double best = 0.0;
  for (const auto& references : overlap.per_segment) {
    std::size_t largest = 0;
    for (const auto& [t, count] : references) {
      (void)t;
      largest = std::max(largest, count);
    }
    best += static_cast<double>(largest);
  }
  return best / static_cast<double>(overlap.pixels);
}

double BoundaryCounts::precision() const {
  return partition_pixels == 0 ? 1.0 : static_cast<double>(precise_pixels) / partition_pixels;
}
double BoundaryCounts::recall() const {
  return reference_pixels == 0 ? 1.0 : static_cast<double>(recalled_pixels) / reference_pixels;
}
double BoundaryCounts::f1() const {
  const double p = precision();
  const double r = recall();
  return p + r > 0.0 ? 2.0 * p * r / (p + r) : 0.0;
}
BoundaryCounts& BoundaryCounts::operator+=(const BoundaryCounts& other) {
  partition_pixels += other.partition_pixels;
  precise_pixels += other.precise_pixels;
  reference_pixels += other.reference_pixels;
  recalled_pixels += other.recalled_pixels;
  return *this;
}

std::vector<BoundaryCounts> boundaryCurve(const cv::Mat& ucm, const cv::Mat& ground_truth,
                                          const cv::Mat& mask, const std::vector<float>& thresholds,
                                          int tolerance_px) {
  if (ucm.type() != CV_32FC1) throw std::invalid_argument("boundaryCurve: ucm must be CV_32FC1");
  if (!mask.empty() && (mask.type() != CV_8UC1 || mask.size() != ucm.size())) {
    throw std::invalid_argument("boundaryCurve: mask must be CV_8UC1 of the image size");
  }
  if (ground_truth.size() != ucm.size() || ground_truth.channels() != 1) {
    throw std::invalid_argument("boundaryCurve: ground truth must be one channel of the ucm size");
  }
  if (tolerance_px < 0) throw std::invalid_argument("boundaryCurve: tolerance_px must be >= 0");
  cv::Mat reference;
  ground_truth.convertTo(reference, CV_32S);
  const cv::Mat reference_boundary = boundaryMap(reference, mask);
  cv::Mat reference_near, ucm_near;  // fresh buffers: dilate must not write into its input
  if (tolerance_px == 0) {
    reference_near = reference_boundary;
    ucm_near = ucm;
  } else {
    // Same square window as boundaryScores; on the ucm the dilation is a max filter, so
    // ucm_near >= t exactly where a boundary pixel of the segmentation at t is within reach.
    const cv::Mat kernel = cv::getStructuringElement(
        cv::MORPH_RECT, cv::Size(2 * tolerance_px + 1, 2 * tolerance_px + 1));
    cv::dilate(reference_boundary, reference_near, kernel);
    cv::dilate(ucm, ucm_near, kernel);
  }
  // Sorted level values: partition pixels, precise ones, and the best level near each reference
  // boundary pixel; the counts at t are then the numbers of values >= t.
  std::vector<float> partition, precise, recalled;
  std::size_t reference_pixels = 0;
  for (int y = 0; y < ucm.rows; ++y) {
    const float* level = ucm.ptr<float>(y);
    const float* level_near = ucm_near.ptr<float>(y);
    const std::uint8_t* ref = reference_boundary.ptr<std::uint8_t>(y);
    const std::uint8_t* ref_near = reference_near.ptr<std::uint8_t>(y);
    for (int x = 0; x < ucm.cols; ++x) {
      if (level[x] >= 0.0f) {
        partition.push_back(level[x]);
        if (ref_near[x] != 0) precise.push_back(level[x]);
      }
      if (ref[x] != 0) {
        ++reference_pixels;
        if (level_near[x] >= 0.0f) recalled.push_back(level_near[x]);
      }
    }
  }
  std::sort(partition.begin(), partition.end());
  std::sort(precise.begin(), precise.end());
  std::sort(recalled.begin(), recalled.end());
  auto at_least = [](const std::vector<float>& values, float t) {
    return static_cast<std::size_t>(values.end() -
                                    std::lower_bound(values.begin(), values.end(), t));
  };
  std::vector<BoundaryCounts> curve(thresholds.size());
  for (std::size_t i = 0; i < thresholds.size(); ++i) {
    // Levels are >= 0, so every t <= 0 gives the full superpixel boundary.
    const float t = std::max(thresholds[i], 0.0f);
    BoundaryCounts& c = curve[i];
    c.threshold = thresholds[i];
    c.partition_pixels = at_least(partition, t);
    c.precise_pixels = at_least(precise, t);
    c.reference_pixels = reference_pixels;
    c.recalled_pixels = at_least(recalled, t);
  }
  return curve;
}

}  // namespace metrics
}  // namespace dasp

#include "dasp/metrics.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>

namespace dasp {
namespace metrics {
namespace {

void checkLabels(const cv::Mat& labels, const char* what) {
  if (labels.empty()) {
    throw std::invalid_argument(std::string(what) + ": label image is empty");
  }
  if (labels.type() != CV_32SC1) {
    throw std::invalid_argument(std::string(what) + ": label image must be CV_32SC1");
  }
}

void checkMask(const cv::Mat& mask, const cv::Size& size, const char* what) {
  if (mask.empty()) return;
  if (mask.type() != CV_8UC1) {
    throw std::invalid_argument(std::string(what) + ": mask must be CV_8UC1");
  }
  if (mask.size() != size) {
    throw std::invalid_argument(std::string(what) + ": mask size differs from the label image");
  }
}

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

inline bool inMask(const cv::Mat& mask, int y, int x) {
  return mask.empty() || mask.at<std::uint8_t>(y, x) != 0;
}

// Maps arbitrary labels to dense indices 0..n-1 in order of first appearance. Negative labels
// (unlabelled) all map to one index when `merge_negative`, otherwise to -1.
class DenseLabels {
 public:
  DenseLabels(const cv::Mat& labels, const cv::Mat& mask, bool merge_negative)
      : index(labels.size(), CV_32SC1, cv::Scalar(-1)) {
    // Superpixel labels are small non-negative numbers: a lookup table is much faster than a
    // hash map. The hash map remains for huge label values.
    int max_label = -1;
    for (int y = 0; y < labels.rows; ++y) {
      const int* row = labels.ptr<int>(y);
      for (int x = 0; x < labels.cols; ++x) {
        if (inMask(mask, y, x)) max_label = std::max(max_label, row[x]);
      }
    }
    const bool use_table = max_label < (1 << 24);
    std::vector<int> table(use_table ? static_cast<std::size_t>(max_label) + 2 : 0, -1);
    std::unordered_map<int, int> map;
    for (int y = 0; y < labels.rows; ++y) {
      const int* row = labels.ptr<int>(y);
      int* out = index.ptr<int>(y);
      for (int x = 0; x < labels.cols; ++x) {
        if (!inMask(mask, y, x)) continue;
        int label = row[x];
        if (label < 0) {
          if (!merge_negative) continue;
          label = -1;
        }
        int* slot = use_table ? &table[static_cast<std::size_t>(label) + 1]
                              : &map.try_emplace(label, -1).first->second;
        if (*slot < 0) {
          *slot = count++;
          original.push_back(label);
        }
        out[x] = *slot;
        ++pixels;
      }
    }
  }
  cv::Mat index;              // CV_32SC1, dense index or -1 outside the domain
  int count = 0;              // number of dense labels
  std::size_t pixels = 0;     // pixels in the domain
  std::vector<int> original;  // dense index -> original label
};

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

ConnectivityScores connectivity(const cv::Mat& labels, const cv::Mat& mask) {
  checkLabels(labels, "connectivity");
  checkMask(mask, labels.size(), "connectivity");
  const DenseLabels segments(labels, mask, false);
  ConnectivityScores scores;
  scores.segments = static_cast<std::size_t>(segments.count);
  if (segments.pixels == 0) return scores;

  // Union-find over pixels; 4-neighbours join when they carry the same segment.
  const int cols = labels.cols;
  const std::size_t total = labels.total();
  std::vector<std::int32_t> parent(total);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&parent](std::int32_t i) {
    while (parent[i] != i) {
      parent[i] = parent[parent[i]];
      i = parent[i];
    }
    return i;
  };
  auto unite = [&](std::int32_t a, std::int32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  };
  for (int y = 0; y < labels.rows; ++y) {
    const int* row = segments.index.ptr<int>(y);
    const int* above = y > 0 ? segments.index.ptr<int>(y - 1) : nullptr;
    for (int x = 0; x < cols; ++x) {
      const int s = row[x];
      if (s < 0) continue;
      const std::int32_t i = y * cols + x;
      if (x > 0 && row[x - 1] == s) unite(i, i - 1);
      if (above != nullptr && above[x] == s) unite(i, i - cols);
    }
  }
  std::vector<std::size_t> component_size(total, 0);  // indexed by the root pixel
  std::vector<std::size_t> segment_size(segments.count, 0);
  for (int y = 0; y < labels.rows; ++y) {
    const int* row = segments.index.ptr<int>(y);
    for (int x = 0; x < cols; ++x) {
      if (row[x] < 0) continue;
      ++component_size[find(y * cols + x)];
      ++segment_size[row[x]];
    }
  }
  std::vector<std::size_t> largest(segments.count, 0);
  std::vector<std::size_t> components(segments.count, 0);
  const int* flat_index = segments.index.ptr<int>(0);  // continuous: created by DenseLabels
  for (std::size_t root = 0; root < total; ++root) {
    const std::size_t size = component_size[root];
    if (size == 0) continue;
    const int s = flat_index[root];
    largest[s] = std::max(largest[s], size);
    ++components[s];
  }
  double weighted = 0.0;
  for (int s = 0; s < segments.count; ++s) {
    weighted += static_cast<double>(segment_size[s] - largest[s]);
    if (components[s] > 1) ++scores.disconnected_segments;
  }
  scores.quotient = weighted / static_cast<double>(segments.pixels);
  return scores;
}

std::size_t countSegments(const cv::Mat& labels, const cv::Mat& mask) {
  checkLabels(labels, "countSegments");
  checkMask(mask, labels.size(), "countSegments");
  return static_cast<std::size_t>(DenseLabels(labels, mask, false).count);
}

namespace {

// Per segment: pixel count and boundary pixel count (a 4-neighbour outside the segment, the mask
// or the image). Optional per-pixel weights for the 3D variant.
struct ShapeSums {
  std::vector<double> area;
  std::vector<double> perimeter;
};

template <typename AreaWeight, typename PerimeterWeight>
ShapeSums shapeSums(const DenseLabels& segments, const cv::Mat& mask, AreaWeight area_weight,
                    PerimeterWeight perimeter_weight) {
  ShapeSums sums;
  sums.area.assign(segments.count, 0.0);
  sums.perimeter.assign(segments.count, 0.0);
  const cv::Mat& index = segments.index;
  (void)mask;
  for (int y = 0; y < index.rows; ++y) {
    const int* row = index.ptr<int>(y);
    for (int x = 0; x < index.cols; ++x) {
      const int s = row[x];
      if (s < 0) continue;
      const double a = area_weight(y, x);
      if (!(a >= 0.0)) continue;  // skip invalid samples (NaN)
      sums.area[s] += a;
      const bool on_boundary = x == 0 || x + 1 == index.cols || y == 0 || y + 1 == index.rows ||
                               row[x - 1] != s || row[x + 1] != s || index.at<int>(y - 1, x) != s ||
                               index.at<int>(y + 1, x) != s;
      if (on_boundary) sums.perimeter[s] += perimeter_weight(y, x);
    }
  }
  return sums;
}

double weightedIpq(const ShapeSums& sums) {
  double total_area = 0.0;
  double weighted = 0.0;
  for (std::size_t s = 0; s < sums.area.size(); ++s) {
    if (sums.area[s] <= 0.0 || sums.perimeter[s] <= 0.0) continue;
    const double ipq = 4.0 * M_PI * sums.area[s] / (sums.perimeter[s] * sums.perimeter[s]);
    weighted += sums.area[s] * ipq;
    total_area += sums.area[s];
  }
  return total_area > 0.0 ? weighted / total_area : 0.0;
}

}  // namespace

double isoperimetricQuotient(const cv::Mat& labels, const cv::Mat& mask) {
  checkLabels(labels, "isoperimetricQuotient");
  checkMask(mask, labels.size(), "isoperimetricQuotient");
  const DenseLabels segments(labels, mask, false);
  if (segments.pixels == 0) {
    throw std::invalid_argument("isoperimetricQuotient: no labelled pixel inside the mask");
  }
  const auto one = [](int, int) { return 1.0; };
  return weightedIpq(shapeSums(segments, mask, one, one));
}

double isoperimetricQuotient3d(const cv::Mat& labels, const cv::Mat& mask, const cv::Mat& depth_m,
                               const cv::Mat& normals, double focal_px, double min_normal_z) {
  const char* what = "isoperimetricQuotient3d";
  checkLabels(labels, what);
  checkMask(mask, labels.size(), what);
  if (depth_m.type() != CV_32FC1 || depth_m.size() != labels.size()) {
    throw std::invalid_argument(
        "isoperimetricQuotient3d: depth must be CV_32FC1 of the label image's size");
  }
  if (normals.type() != CV_32FC3 || normals.size() != labels.size()) {
    throw std::invalid_argument(
        "isoperimetricQuotient3d: normals must be CV_32FC3 of the label image's size");
  }
  if (!(focal_px > 0.0) || !std::isfinite(focal_px)) {
    throw std::invalid_argument("isoperimetricQuotient3d: focal length must be positive");
  }
  if (!(min_normal_z > 0.0 && min_normal_z <= 1.0)) {
    throw std::invalid_argument("isoperimetricQuotient3d: min_normal_z must be in (0, 1]");
  }
  // Restrict the domain to pixels with valid depth and normal so that boundaries of holes count.
  cv::Mat valid(labels.size(), CV_8UC1, cv::Scalar(0));
  for (int y = 0; y < labels.rows; ++y) {
    for (int x = 0; x < labels.cols; ++x) {
      if (!inMask(mask, y, x)) continue;
      const float d = depth_m.at<float>(y, x);
      const cv::Vec3f n = normals.at<cv::Vec3f>(y, x);
      if (std::isfinite(d) && d > 0.0f && std::isfinite(n[0]) && std::isfinite(n[1]) &&
          std::isfinite(n[2])) {
        valid.at<std::uint8_t>(y, x) = 255;
      }
    }
  }
  const DenseLabels segments(labels, valid, false);
  if (segments.pixels == 0) {
    throw std::invalid_argument(
        "isoperimetricQuotient3d: no labelled pixel with valid depth inside the mask");
  }
  const double inv_f = 1.0 / focal_px;
  auto stretch = [&](int y, int x) {
    return 1.0 /
           std::max(min_normal_z, std::abs(static_cast<double>(normals.at<cv::Vec3f>(y, x)[2])));
  };
  const auto area = [&](int y, int x) {
    const double d = depth_m.at<float>(y, x);
    return d * d * inv_f * inv_f * stretch(y, x);
  };
  const auto perimeter = [&](int y, int x) {
    return static_cast<double>(depth_m.at<float>(y, x)) * inv_f * stretch(y, x);
  };
  return weightedIpq(shapeSums(segments, valid, area, perimeter));
}

CompressionScores compressionScores(const cv::Mat& labels, const cv::Mat& mask,
                                    const cv::Mat& features, FeatureMean mean) {
  const char* what = "compressionScores";
  checkLabels(labels, what);
  checkMask(mask, labels.size(), what);
  if (features.size() != labels.size()) {
    throw std::invalid_argument("compressionScores: feature image size differs from the labels");
  }
  cv::Mat values;
  if (features.depth() == CV_32F && features.channels() >= 1 && features.channels() <= 4) {
    values = features;
  } else if (features.type() == CV_8UC3 || features.type() == CV_8UC1 ||
             features.type() == CV_16UC1) {
    features.convertTo(values, CV_MAKETYPE(CV_32F, features.channels()));
  } else {
    throw std::invalid_argument(
        "compressionScores: features must be CV_32FC1..4, CV_8UC1/3 or CV_16UC1");
  }
  const int channels = values.channels();
  // Domain: mask and finite feature.
  cv::Mat valid(labels.size(), CV_8UC1, cv::Scalar(0));
  for (int y = 0; y < labels.rows; ++y) {
    const float* row = values.ptr<float>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (!inMask(mask, y, x)) continue;
      bool finite = true;
      for (int c = 0; c < channels; ++c) finite = finite && std::isfinite(row[x * channels + c]);
      if (finite) valid.at<std::uint8_t>(y, x) = 255;
    }
  }
  const DenseLabels segments(labels, valid, true);
  if (segments.pixels == 0) {
    throw std::invalid_argument("compressionScores: no pixel with a finite feature in the mask");
  }
  std::vector<double> sums(static_cast<std::size_t>(segments.count) * channels, 0.0);
  std::vector<std::size_t> sizes(segments.count, 0);
  std::vector<double> global(channels, 0.0);
  for (int y = 0; y < labels.rows; ++y) {
    const int* row = segments.index.ptr<int>(y);
    const float* f = values.ptr<float>(y);
    for (int x = 0; x < labels.cols; ++x) {
      const int s = row[x];
      if (s < 0) continue;
      ++sizes[s];
      for (int c = 0; c < channels; ++c) {
        sums[s * channels + c] += f[x * channels + c];
        global[c] += f[x * channels + c];
      }
    }
  }
  auto finishMean = [&](double* m, double count) {
    for (int c = 0; c < channels; ++c) m[c] /= count;
    if (mean == FeatureMean::kUnitVector) {
      double norm = 0.0;
      for (int c = 0; c < channels; ++c) norm += m[c] * m[c];
      norm = std::sqrt(norm);
      if (norm > 0.0) {
        for (int c = 0; c < channels; ++c) m[c] /= norm;
      }
    }
  };
  for (int s = 0; s < segments.count; ++s) {
    finishMean(&sums[s * channels], static_cast<double>(sizes[s]));
  }
  finishMean(global.data(), static_cast<double>(segments.pixels));

  double residual = 0.0;
  double total = 0.0;
  for (int y = 0; y < labels.rows; ++y) {
    const int* row = segments.index.ptr<int>(y);
    const float* f = values.ptr<float>(y);
    for (int x = 0; x < labels.cols; ++x) {
      const int s = row[x];
      if (s < 0) continue;
      for (int c = 0; c < channels; ++c) {
        const double v = f[x * channels + c];
        const double r = v - sums[s * channels + c];
        const double g = v - global[c];
        residual += r * r;
        total += g * g;
      }
    }
  }
  double explained = 0.0;
  for (int s = 0; s < segments.count; ++s) {
    double d2 = 0.0;
    for (int c = 0; c < channels; ++c) {
      const double d = sums[s * channels + c] - global[c];
      d2 += d * d;
    }
    explained += static_cast<double>(sizes[s]) * d2;
  }
  CompressionScores scores;
  scores.pixels = segments.pixels;
  scores.compression_error = std::sqrt(residual / static_cast<double>(segments.pixels));
  // A constant feature has nothing to explain: every partition explains it fully.
  scores.explained_variation = total > 0.0 ? explained / total : 1.0;
  return scores;
}

std::vector<cv::Point2d> segmentCentroids(const cv::Mat& labels, const cv::Mat& mask) {
  checkLabels(labels, "segmentCentroids");
  checkMask(mask, labels.size(), "segmentCentroids");
  const DenseLabels segments(labels, mask, false);
  std::vector<cv::Point2d> sums(segments.count, cv::Point2d(0.0, 0.0));
  std::vector<std::size_t> sizes(segments.count, 0);
  for (int y = 0; y < labels.rows; ++y) {
    const int* row = segments.index.ptr<int>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (row[x] < 0) continue;
      sums[row[x]] += cv::Point2d(x, y);
      ++sizes[row[x]];
    }
  }
  // Report in label order.
  std::vector<int> order(segments.count);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return segments.original[a] < segments.original[b]; });
  std::vector<cv::Point2d> centroids;
  centroids.reserve(segments.count);
  for (int s : order) centroids.push_back(sums[s] / static_cast<double>(sizes[s]));
  return centroids;
}

UniformDistributionScores uniformDistributionError(const cv::Mat& labels, const cv::Mat& mask) {
  checkLabels(labels, "uniformDistributionError");
  checkMask(mask, labels.size(), "uniformDistributionError");
  const std::vector<cv::Point2d> centroids = segmentCentroids(labels, mask);
  const double domain = mask.empty() ? static_cast<double>(labels.total())
                                     : static_cast<double>(cv::countNonZero(mask));
  if (domain == 0.0 || centroids.empty()) {
    throw std::invalid_argument("uniformDistributionError: no labelled pixel inside the mask");
  }
  const double rho0 = static_cast<double>(centroids.size()) / domain;
  UniformDistributionScores scores;
  // k_sigma(0) = 1 / (2 pi sigma^2) = rho0.
  scores.sigma_px = std::sqrt(1.0 / (2.0 * M_PI * rho0));
  // rho_C: unit-mass Gaussian kernels at the centroids (bilinear splat, then Gaussian filter with
  // a normalised kernel, so each centroid keeps mass 1).
  cv::Mat deltas(labels.size(), CV_64FC1, cv::Scalar(0.0));
  for (const cv::Point2d& c : centroids) {
    const int x0 = static_cast<int>(std::floor(c.x));
    const int y0 = static_cast<int>(std::floor(c.y));
    const double fx = c.x - x0;
    const double fy = c.y - y0;
    const int xs[2] = {x0, std::min(x0 + 1, labels.cols - 1)};
    const int ys[2] = {y0, std::min(y0 + 1, labels.rows - 1)};
    const double wx[2] = {1.0 - fx, fx};
    const double wy[2] = {1.0 - fy, fy};
    for (int j = 0; j < 2; ++j) {
      for (int i = 0; i < 2; ++i) deltas.at<double>(ys[j], xs[i]) += wx[i] * wy[j];
    }
  }
  cv::Mat density;
  const int radius = static_cast<int>(std::ceil(4.0 * scores.sigma_px));
  cv::GaussianBlur(deltas, density, cv::Size(2 * radius + 1, 2 * radius + 1), scores.sigma_px,
                   scores.sigma_px, cv::BORDER_CONSTANT);
  double sum_sq = 0.0;
  for (int y = 0; y < labels.rows; ++y) {
    const double* row = density.ptr<double>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (!inMask(mask, y, x)) continue;
      const double d = row[x] - rho0;
      sum_sq += d * d;
    }
  }
  scores.error = std::sqrt(sum_sq);
  scores.relative_rms = std::sqrt(sum_sq / domain) / rho0;
  return scores;
}

double relativeDensityError(const cv::Mat& density, const std::vector<cv::Point2d>& points,
                            const cv::Mat& mask) {
  if (density.empty() || density.channels() != 1 ||
      (density.depth() != CV_32F && density.depth() != CV_64F)) {
    throw std::invalid_argument("relativeDensityError: density must be CV_32FC1 or CV_64FC1");
  }
  checkMask(mask, density.size(), "relativeDensityError");
  cv::Mat rho;
  density.convertTo(rho, CV_64F);
  double minimum = 0.0;
  cv::minMaxLoc(rho, &minimum);
  if (!(minimum >= 0.0) || !cv::checkRange(rho)) {
    throw std::invalid_argument("relativeDensityError: density must be finite and >= 0");
  }
  cv::Mat approximation(rho.size(), CV_64FC1, cv::Scalar(0.0));
  for (const cv::Point2d& p : points) {
    if (!(p.x >= 0.0 && p.y >= 0.0 && p.x <= rho.cols - 1 && p.y <= rho.rows - 1)) {
      throw std::invalid_argument("relativeDensityError: point outside the image");
    }
    const double rho_p =
        rho.at<double>(static_cast<int>(std::lround(p.y)), static_cast<int>(std::lround(p.x)));
    if (rho_p <= 0.0) continue;  // a kernel of zero density has infinite extent and zero height
    // exp(-pi rho d^2) drops below 1e-6 of its peak at d^2 = ln(1e6) / (pi rho).
    const double reach = std::sqrt(std::log(1e6) / (M_PI * rho_p));
    const int x0 = std::max(0, static_cast<int>(std::floor(p.x - reach)));
    const int x1 = std::min(rho.cols - 1, static_cast<int>(std::ceil(p.x + reach)));
    const int y0 = std::max(0, static_cast<int>(std::floor(p.y - reach)));
    const int y1 = std::min(rho.rows - 1, static_cast<int>(std::ceil(p.y + reach)));
    for (int y = y0; y <= y1; ++y) {
      double* row = approximation.ptr<double>(y);
      const double dy2 = (y - p.y) * (y - p.y);
      for (int x = x0; x <= x1; ++x) {
        const double d2 = (x - p.x) * (x - p.x) + dy2;
        row[x] += rho_p * std::exp(-M_PI * rho_p * d2);
      }
    }
  }
  double error = 0.0;
  double mass = 0.0;
  for (int y = 0; y < rho.rows; ++y) {
    const double* r = rho.ptr<double>(y);
    const double* a = approximation.ptr<double>(y);
    for (int x = 0; x < rho.cols; ++x) {
      if (!inMask(mask, y, x)) continue;
      error += std::abs(a[x] - r[x]);
      mass += r[x];
    }
  }
  if (!(mass > 0.0)) {
    throw std::invalid_argument("relativeDensityError: density integrates to zero over the mask");
  }
  return error / mass;
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

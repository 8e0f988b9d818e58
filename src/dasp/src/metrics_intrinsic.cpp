// Metrics of a partition alone, without a reference (thesis appendix A): connectivity, segment
// count, 2D and 3D isoperimetric quotient, compression error and explained variation, uniform
// distribution and relative density error.
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

#include "dasp/metrics.h"
#include "metrics_common.h"

namespace dasp {
namespace metrics {

using detail::checkLabels;
using detail::checkMask;
using detail::DenseLabels;
using detail::inMask;

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

}  // namespace metrics
}  // namespace dasp

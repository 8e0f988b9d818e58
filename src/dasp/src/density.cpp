// Densities (thesis §2.2, §3.2.2) and the superpixel radius for a count (eq. 3.17).
#include "dasp/density.h"

#include <cmath>
#include <stdexcept>

#include "depth_exponent.h"

namespace dasp {
namespace {

constexpr float kPi = 3.14159265358979f;

bool finitePositive(float value) { return std::isfinite(value) && value > 0.0f; }

// (z / 1 m)^(a - 2) for k = 2 (2 - a) >= 1 factors of 1 / sqrt(z); 0 where z <= 0 (invalid
// depth). The callers skip it for k = 0 (a = 2), where the weight is 1.
inline float depthWeight(float z, int k) {
  const float s = z > 0.0f ? 1.0f / std::sqrt(z) : 0.0f;
  float w = s;
  for (int i = 1; i < k; ++i) w *= s;
  return w;
}

}  // namespace

float radiusAtDepth(float radius_m, float depth_m, float depth_exponent) {
  const int k = detail::inverseRootFactors(depth_exponent);
  if (k == 0 || !(depth_m > 0.0f)) return radius_m;
  const float q = std::sqrt(std::sqrt(depth_m));  // z^(1/4): R z^((2 - a) / 2) = R q^k
  float r = radius_m;
  for (int i = 0; i < k; ++i) r *= q;
  return r;
}

float radiusForCount(const PixelFeatures& features, int count, float depth_exponent) {
  if (!features.hasDepth()) throw std::invalid_argument("radiusForCount: features have no depth");
  if (count < 1) throw std::invalid_argument("radiusForCount: count must be >= 1");
  const int k = detail::inverseRootFactors(depth_exponent);
  double total_area = 0.0;
  if (k == 0) {
    for (float a : features.area) total_area += a;
  } else {
    for (std::size_t i = 0; i < features.size(); ++i) {
      total_area += features.area[i] * depthWeight(features.z[i], k);
    }
  }
  if (!(total_area > 0.0)) throw std::invalid_argument("radiusForCount: no valid surface area");
  return static_cast<float>(std::sqrt(total_area / (kPi * count)));
}

cv::Mat computeDepthDensity(const PixelFeatures& features, float radius_m, float depth_exponent) {
  cv::Mat density;
  computeDepthDensity(features, radius_m, density, depth_exponent);
  return density;
}

void computeDepthDensity(const PixelFeatures& features, float radius_m, cv::Mat& density,
                         float depth_exponent) {
  if (!features.hasDepth()) {
    throw std::invalid_argument("computeDepthDensity: features have no depth");
  }
  if (!finitePositive(radius_m)) {
    throw std::invalid_argument("computeDepthDensity: radius must be finite and positive");
  }
  const int k = detail::inverseRootFactors(depth_exponent);
  density.create(features.height, features.width, CV_32FC1);
  const float scale = 1.0f / (kPi * radius_m * radius_m);
  float* out = density.ptr<float>();
  if (k == 0) {
    for (std::size_t i = 0; i < features.size(); ++i) out[i] = features.area[i] * scale;
  } else {
    for (std::size_t i = 0; i < features.size(); ++i) {
      out[i] = features.area[i] * scale * depthWeight(features.z[i], k);
    }
  }
}

cv::Mat computeConstantDensity(const PixelFeatures& features, int count) {
  if (count < 1 || count > features.valid_count) {
    throw std::invalid_argument("computeConstantDensity: count must be in [1, valid pixels]");
  }
  cv::Mat density(features.height, features.width, CV_32FC1);
  const float value = static_cast<float>(count) / static_cast<float>(features.valid_count);
  float* out = density.ptr<float>();
  for (std::size_t i = 0; i < features.size(); ++i) out[i] = features.valid[i] ? value : 0.0f;
  return density;
}

double densityIntegral(const cv::Mat& density) {
  if (density.type() != CV_32FC1) throw std::invalid_argument("density must be CV_32FC1");
  double sum = 0.0;
  for (int row = 0; row < density.rows; ++row) {
    const float* p = density.ptr<float>(row);
    double row_sum = 0.0;
    for (int col = 0; col < density.cols; ++col) row_sum += p[col];
    sum += row_sum;
  }
  return sum;
}

float daspRadius(const PixelFeatures& features, const DaspConfig& config) {
  return config.size_mode == SizeMode::kCount
             ? radiusForCount(features, config.superpixel_count, config.experimental.depth_exponent)
             : config.radius_m;
}

}  // namespace dasp

// Input checks, per-pixel features (thesis §3.2.1) and densities (§3.2.2).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "dasp/stages.h"
#include "parallel.h"

namespace dasp {
namespace {

constexpr float kPi = 3.14159265358979f;

bool finitePositive(float value) { return std::isfinite(value) && value > 0.0f; }

void requireColor(const cv::Mat& color, const char* what) {
  if (color.empty()) throw std::invalid_argument(std::string(what) + ": colour image is empty");
  if (color.type() != CV_8UC3) {
    throw std::invalid_argument(std::string(what) +
                                ": colour image must be CV_8UC3 (8-bit BGR), got type " +
                                std::to_string(color.type()));
  }
}

}  // namespace

void validateInput(const RgbdFrame& frame, const DaspConfig& config) {
  requireColor(frame.color, "DASP");
  if (frame.depth.empty()) throw std::invalid_argument("DASP: depth image is empty");
  if (frame.depth.type() != CV_16UC1 && frame.depth.type() != CV_32FC1) {
    throw std::invalid_argument(
        "DASP: depth image must be CV_16UC1 (millimetres) or CV_32FC1 (metres), got type " +
        std::to_string(frame.depth.type()));
  }
  if (frame.color.size() != frame.depth.size()) {
    throw std::invalid_argument("DASP: colour (" + std::to_string(frame.color.cols) + "x" +
                                std::to_string(frame.color.rows) + ") and depth (" +
                                std::to_string(frame.depth.cols) + "x" +
                                std::to_string(frame.depth.rows) + ") sizes differ");
  }
  const Intrinsics& k = frame.intrinsics;
  const float width = static_cast<float>(frame.depth.cols);
  const float height = static_cast<float>(frame.depth.rows);
  if (!finitePositive(k.fx) || !finitePositive(k.fy)) {
    throw std::invalid_argument("DASP: focal lengths fx, fy must be finite and positive");
  }
  if (!std::isfinite(k.cx) || !std::isfinite(k.cy) || k.cx < -width || k.cx > 2.0f * width ||
      k.cy < -height || k.cy > 2.0f * height) {
    throw std::invalid_argument(
        "DASP: principal point (cx, cy) must be finite and near the image (within one image "
        "size of it)");
  }
  if (k.fx / k.fy > 10.0f || k.fy / k.fx > 10.0f) {
    throw std::invalid_argument("DASP: fx and fy differ by more than a factor 10");
  }
  const long long pixels = static_cast<long long>(frame.depth.cols) * frame.depth.rows;
  if (config.size_mode == SizeMode::kCount) {
    if (config.superpixel_count < 1 || config.superpixel_count > pixels) {
      throw std::invalid_argument("DASP: superpixel_count must be in [1, pixel count " +
                                  std::to_string(pixels) + "], got " +
                                  std::to_string(config.superpixel_count));
    }
  } else if (!finitePositive(config.radius_m)) {
    throw std::invalid_argument("DASP: radius_m must be finite and positive in radius mode");
  }
  if (config.iterations < 1) throw std::invalid_argument("DASP: iterations must be >= 1");
  if (!(config.weight_spatial >= 0.0f) || !(config.weight_color >= 0.0f) ||
      !(config.weight_normal >= 0.0f) || !std::isfinite(config.weight_spatial) ||
      !std::isfinite(config.weight_color) || !std::isfinite(config.weight_normal)) {
    throw std::invalid_argument("DASP: metric weights must be finite and >= 0");
  }
  if (!finitePositive(config.window_multiple)) {
    throw std::invalid_argument("DASP: window_multiple must be finite and positive");
  }
  if (!(config.min_size_fraction >= 0.0f) || !(config.min_size_fraction < 1.0f)) {
    throw std::invalid_argument("DASP: min_size_fraction must be in [0, 1)");
  }
  if (!(config.max_slant_factor >= 1.0f) || !std::isfinite(config.max_slant_factor)) {
    throw std::invalid_argument("DASP: max_slant_factor must be finite and >= 1");
  }
  if (config.normal_step_px < 1) throw std::invalid_argument("DASP: normal_step_px must be >= 1");
  if (!finitePositive(config.depth_jump_ratio)) {
    throw std::invalid_argument("DASP: depth_jump_ratio must be finite and positive");
  }
  if (config.threads < 0) throw std::invalid_argument("DASP: threads must be >= 0");
}

PixelFeatures computeColorFeatures(const cv::Mat& color) {
  requireColor(color, "ASP");
  PixelFeatures features;
  features.width = color.cols;
  features.height = color.rows;
  const std::size_t n = features.size();
  features.r.resize(n);
  features.g.resize(n);
  features.b.resize(n);
  features.valid.assign(n, 1);
  features.valid_count = static_cast<int>(n);
  for (int row = 0; row < color.rows; ++row) {
    const cv::Vec3b* src = color.ptr<cv::Vec3b>(row);
    const std::size_t base = static_cast<std::size_t>(row) * color.cols;
    for (int col = 0; col < color.cols; ++col) {
      features.b[base + col] = src[col][0] * (1.0f / 255.0f);
      features.g[base + col] = src[col][1] * (1.0f / 255.0f);
      features.r[base + col] = src[col][2] * (1.0f / 255.0f);
    }
  }
  return features;
}

PixelFeatures computeFeatures(const RgbdFrame& frame, const DaspConfig& config) {
  validateInput(frame, config);
  PixelFeatures features = computeColorFeatures(frame.color);
  features.intrinsics = frame.intrinsics;
  const int width = features.width;
  const int height = features.height;
  const std::size_t n = features.size();
  features.x.assign(n, 0.0f);
  features.y.assign(n, 0.0f);
  features.z.assign(n, 0.0f);
  features.nx.assign(n, 0.0f);
  features.ny.assign(n, 0.0f);
  features.nz.assign(n, 0.0f);
  features.area.assign(n, 0.0f);
  const Intrinsics k = frame.intrinsics;
  const float inv_fx = 1.0f / k.fx;
  const float inv_fy = 1.0f / k.fy;

  // Pass 1: depth and 3D points (eq. 3.4).
  const bool millimetres = frame.depth.type() == CV_16UC1;
  detail::forChunks(height, 16, config.threads, [&](int, int row_begin, int row_end) {
    for (int row = row_begin; row < row_end; ++row) {
      const float ray_y = (static_cast<float>(row) - k.cy) * inv_fy;
      const std::size_t base = static_cast<std::size_t>(row) * width;
      float* z = features.z.data() + base;
      if (millimetres) {
        const std::uint16_t* src = frame.depth.ptr<std::uint16_t>(row);
        for (int col = 0; col < width; ++col) z[col] = 0.001f * static_cast<float>(src[col]);
      } else {
        const float* src = frame.depth.ptr<float>(row);
        for (int col = 0; col < width; ++col) {
          z[col] = (std::isfinite(src[col]) && src[col] > 0.0f) ? src[col] : 0.0f;
        }
      }
      float* x = features.x.data() + base;
      float* y = features.y.data() + base;
      std::uint8_t* valid = features.valid.data() + base;
      for (int col = 0; col < width; ++col) {
        valid[col] = z[col] > 0.0f ? 1 : 0;
        x[col] = z[col] * (static_cast<float>(col) - k.cx) * inv_fx;
        y[col] = z[col] * ray_y;
      }
    }
  });
  int valid_count = 0;
  for (std::uint8_t v : features.valid) valid_count += v;
  features.valid_count = valid_count;
  if (valid_count == 0) {
    throw std::invalid_argument("DASP: the depth image has no valid pixel (all zero, NaN or <= 0)");
  }
  if (config.size_mode == SizeMode::kCount && config.superpixel_count > valid_count) {
    throw std::invalid_argument(
        "DASP: superpixel_count " + std::to_string(config.superpixel_count) +
        " exceeds the number of pixels with valid depth (" + std::to_string(valid_count) + ")");
  }

  // Pass 2: robust depth derivatives (eq. 3.6, 3.7), normals and pixel surface area. A neighbour
  // across a depth jump is ignored and the one-sided difference is used (robust at edges).
  const int step = config.normal_step_px;
  const float jump = config.depth_jump_ratio;
  const float max_slant = config.max_slant_factor;
  const std::vector<float>& z = features.z;
  const auto derivative = [&](std::size_t i, int coord, int limit, std::ptrdiff_t stride) {
    const float zc = z[i];
    for (int h = step; h >= 1; h = (h == 1 ? 0 : 1)) {
      const bool has_minus = coord - h >= 0;
      const bool has_plus = coord + h < limit;
      const float zm = has_minus ? z[i - h * stride] : 0.0f;
      const float zp = has_plus ? z[i + h * stride] : 0.0f;
      const bool ok_minus = zm > 0.0f && std::abs(zm - zc) <= jump * zc;
      const bool ok_plus = zp > 0.0f && std::abs(zp - zc) <= jump * zc;
      if (ok_minus && ok_plus) return (zp - zm) / (2.0f * h);
      if (ok_plus) return (zp - zc) / h;
      if (ok_minus) return (zc - zm) / h;
    }
    return 0.0f;
  };
  detail::forChunks(height, 16, config.threads, [&](int, int row_begin, int row_end) {
    for (int row = row_begin; row < row_end; ++row) {
      const float ray_y = (static_cast<float>(row) - k.cy) * inv_fy;
      for (int col = 0; col < width; ++col) {
        const std::size_t i = static_cast<std::size_t>(row) * width + col;
        if (!features.valid[i]) continue;
        const float zc = z[i];
        const float dz_du = derivative(i, col, width, 1);
        const float dz_dv = derivative(i, row, height, width);
        const float ray_x = (static_cast<float>(col) - k.cx) * inv_fx;
        // Normal = tangent_u x tangent_v of the back-projected surface P = z(u, v) ray(u, v),
        // tangent_u = dz_du ray + (z / fx, 0, 0), tangent_v = dz_dv ray + (0, z / fy, 0),
        // expanded by hand; its length is the pixel's 3D area.
        float nx = -dz_du * zc * inv_fy;
        float ny = -dz_dv * zc * inv_fx;
        float nz = zc * (dz_du * ray_x * inv_fy + dz_dv * ray_y * inv_fx + zc * inv_fx * inv_fy);
        const float norm = std::sqrt(nx * nx + ny * ny + nz * nz);
        const float frontal_area = zc * zc * inv_fx * inv_fy;
        float scale = 1.0f / norm;
        if (nx * ray_x + ny * ray_y + nz > 0.0f) scale = -scale;  // eq. 3.9: towards the camera
        features.nx[i] = nx * scale;
        features.ny[i] = ny * scale;
        features.nz[i] = nz * scale;
        features.area[i] = std::min(norm, max_slant * frontal_area);
      }
    }
  });
  return features;
}

float radiusForCount(const PixelFeatures& features, int count) {
  if (!features.hasDepth()) throw std::invalid_argument("radiusForCount: features have no depth");
  if (count < 1) throw std::invalid_argument("radiusForCount: count must be >= 1");
  double total_area = 0.0;
  for (float a : features.area) total_area += a;
  if (!(total_area > 0.0)) throw std::invalid_argument("radiusForCount: no valid surface area");
  return static_cast<float>(std::sqrt(total_area / (kPi * count)));
}

cv::Mat computeDepthDensity(const PixelFeatures& features, float radius_m) {
  if (!features.hasDepth()) {
    throw std::invalid_argument("computeDepthDensity: features have no depth");
  }
  if (!finitePositive(radius_m)) {
    throw std::invalid_argument("computeDepthDensity: radius must be finite and positive");
  }
  cv::Mat density(features.height, features.width, CV_32FC1);
  const float scale = 1.0f / (kPi * radius_m * radius_m);
  float* out = density.ptr<float>();
  for (std::size_t i = 0; i < features.size(); ++i) out[i] = features.area[i] * scale;
  return density;
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

}  // namespace dasp

// Input checks and per-pixel features (thesis §3.2.1).
#include "dasp/features.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "depth_exponent.h"
#include "parallel.h"
#include "simd.h"

namespace dasp {
namespace {

constexpr int kFeatureChunks = 16;  // row stripes of the per-pixel passes

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
  for (const float weight : {config.weight_spatial, config.weight_color, config.weight_normal,
                             config.experimental.weight_depth}) {
    if (!(weight >= 0.0f) || !std::isfinite(weight)) {
      throw std::invalid_argument("DASP: metric weights must be finite and >= 0");
    }
  }
  if (!finitePositive(config.window_multiple)) {
    throw std::invalid_argument("DASP: window_multiple must be finite and positive");
  }
  if (!(config.min_size_fraction >= 0.0f) || !(config.min_size_fraction < 1.0f)) {
    throw std::invalid_argument("DASP: min_size_fraction must be in [0, 1)");
  }
  const float max_slant_factor = config.experimental.max_slant_factor;
  if (!(max_slant_factor >= 1.0f) || !std::isfinite(max_slant_factor)) {
    throw std::invalid_argument("DASP: max_slant_factor must be finite and >= 1");
  }
  if (config.normal_step_px < 1) throw std::invalid_argument("DASP: normal_step_px must be >= 1");
  detail::inverseRootFactors(config.experimental.depth_exponent);  // throws with the reason
  if (!finitePositive(config.depth_jump_ratio)) {
    throw std::invalid_argument("DASP: depth_jump_ratio must be finite and positive");
  }
  if (config.threads < 0) throw std::invalid_argument("DASP: threads must be >= 0");
}

namespace {

// Sizes the feature arrays for an image; keeps their storage (and contents) when the size is
// unchanged, so that a stream of frames allocates and clears nothing.
void resizeFeatures(PixelFeatures& features, int width, int height, bool depth) {
  features.width = width;
  features.height = height;
  const std::size_t n = features.size();
  for (PixelVector<float>* v : {&features.r, &features.g, &features.b}) v->resize(n);
  features.valid.resize(n);
  for (PixelVector<float>* v : {&features.x, &features.y, &features.z, &features.nx, &features.ny,
                                &features.nz, &features.area}) {
    if (depth) {
      v->resize(n);
    } else {
      v->clear();
    }
  }
}

DASP_ALWAYS_INLINE void colorRow(const cv::Vec3b* src, int width, float* r, float* g, float* b) {
  for (int col = 0; col < width; ++col) {
    b[col] = src[col][0] * (1.0f / 255.0f);
    g[col] = src[col][1] * (1.0f / 255.0f);
    r[col] = src[col][2] * (1.0f / 255.0f);
  }
}

// Robust depth derivative along one axis from the depths at -h, -1, 0, +1, +h (eq. 3.6, 3.7):
// the central difference at step h if both neighbours lie on the same surface (|dz| <= jump z),
// else the one-sided difference on the side that does, then the same at step 1, else 0.
// Branch-free so that the row loops below vectorise.
inline float robustDerivative(float zmh, float zm1, float zc, float zp1, float zph, float h,
                              float jump) {
  const float tolerance = jump * zc;
  const bool ok_mh = (zmh > 0.0f) & (std::abs(zmh - zc) <= tolerance);
  const bool ok_ph = (zph > 0.0f) & (std::abs(zph - zc) <= tolerance);
  const bool ok_m1 = (zm1 > 0.0f) & (std::abs(zm1 - zc) <= tolerance);
  const bool ok_p1 = (zp1 > 0.0f) & (std::abs(zp1 - zc) <= tolerance);
  const float inv_h = 1.0f / h;
  // All candidates are computed unconditionally and then selected, without branches.
  const float backward_1 = zc - zm1, forward_1 = zp1 - zc, central_1 = 0.5f * (zp1 - zm1);
  const float backward_h = (zc - zmh) * inv_h, forward_h = (zph - zc) * inv_h;
  const float central_h = 0.5f * (zph - zmh) * inv_h;
  float d = ok_m1 ? backward_1 : 0.0f;
  d = ok_p1 ? forward_1 : d;
  d = ok_m1 & ok_p1 ? central_1 : d;
  d = ok_mh ? backward_h : d;
  d = ok_ph ? forward_h : d;
  d = ok_mh & ok_ph ? central_h : d;
  return d;
}

struct NormalParams {
  float inv_fx, inv_fy, cx, max_slant;
};

// Normal (towards the camera, eq. 3.8, 3.9) and 3D area of one pixel from its depth derivatives:
// normal = tangent_u x tangent_v of the back-projected surface P = z(u, v) ray(u, v), with
// tangent_u = dz_du ray + (z / fx, 0, 0) and tangent_v = dz_dv ray + (0, z / fy, 0), expanded
// by hand; its length is the pixel's 3D area.
inline void normalAndArea(float zc, float dz_du, float dz_dv, float ray_x, float ray_y,
                          const NormalParams& p, float& nx_out, float& ny_out, float& nz_out,
                          float& area_out) {
  const float nx = -dz_du * zc * p.inv_fy;
  const float ny = -dz_dv * zc * p.inv_fx;
  const float nz =
      zc * (dz_du * ray_x * p.inv_fy + dz_dv * ray_y * p.inv_fx + zc * p.inv_fx * p.inv_fy);
  const float norm = std::sqrt(nx * nx + ny * ny + nz * nz);
  // Invalid pixels (zc = 0) have n = 0 and area 0 without a select; the division is
  // unconditional, so that the loop vectorises.
  const float magnitude = 1.0f / std::max(norm, 1e-30f);
  const float scale = nx * ray_x + ny * ray_y + nz > 0.0f ? -magnitude : magnitude;
  const float frontal_area = zc * zc * p.inv_fx * p.inv_fy;
  nx_out = nx * scale;
  ny_out = ny * scale;
  nz_out = nz * scale;
  area_out = std::min(norm, p.max_slant * frontal_area);
}

// Interior of one row (columns [begin, end) have all neighbours in the image): vectorised.
DASP_VECTOR_CLONES void normalRowInterior(const float* __restrict z, std::ptrdiff_t stride,
                                          int step, float jump, float ray_y, const NormalParams p,
                                          int begin, int end, float* __restrict nx,
                                          float* __restrict ny, float* __restrict nz,
                                          float* __restrict area) {
  const float h = static_cast<float>(step);
  for (int col = begin; col < end; ++col) {
    const float zc = z[col];
    const float dz_du =
        robustDerivative(z[col - step], z[col - 1], zc, z[col + 1], z[col + step], h, jump);
    const float dz_dv = robustDerivative(z[col - step * stride], z[col - stride], zc,
                                         z[col + stride], z[col + step * stride], h, jump);
    const float ray_x = (static_cast<float>(col) - p.cx) * p.inv_fx;
    normalAndArea(zc, dz_du, dz_dv, ray_x, ray_y, p, nx[col], ny[col], nz[col], area[col]);
  }
}

// Colour, depth (metres), 3D point (eq. 3.4) and validity of one row; returns the number of
// valid pixels. Depth is CV_16UC1 millimetres (depth_mm) or CV_32FC1 metres (depth_m).
DASP_VECTOR_CLONES int pointRow(const cv::Vec3b* __restrict bgr,
                                const std::uint16_t* __restrict depth_mm,
                                const float* __restrict depth_m, int width, float inv_fx, float cx,
                                float ray_y, float* __restrict r, float* __restrict g,
                                float* __restrict b, float* __restrict x, float* __restrict y,
                                float* __restrict z, std::uint8_t* __restrict valid) {
  colorRow(bgr, width, r, g, b);
  if (depth_mm != nullptr) {
    for (int col = 0; col < width; ++col) z[col] = 0.001f * static_cast<float>(depth_mm[col]);
  } else {
    for (int col = 0; col < width; ++col) {
      const float d = depth_m[col];
      // NaN, infinity and values <= 0 are invalid (comparisons with NaN are false).
      z[col] = (d > 0.0f) & (d <= std::numeric_limits<float>::max()) ? d : 0.0f;
    }
  }
  int count = 0;
  for (int col = 0; col < width; ++col) {
    const bool ok = z[col] > 0.0f;
    valid[col] = ok ? 1 : 0;
    count += ok ? 1 : 0;
    x[col] = z[col] * (static_cast<float>(col) - cx) * inv_fx;
    y[col] = z[col] * ray_y;
  }
  return count;
}

}  // namespace

PixelFeatures computeColorFeatures(const cv::Mat& color) {
  requireColor(color, "ASP");
  PixelFeatures features;
  resizeFeatures(features, color.cols, color.rows, false);
  std::fill(features.valid.begin(), features.valid.end(), std::uint8_t{1});
  features.valid_count = static_cast<int>(features.size());
  for (int row = 0; row < color.rows; ++row) {
    const std::size_t base = static_cast<std::size_t>(row) * color.cols;
    colorRow(color.ptr<cv::Vec3b>(row), color.cols, features.r.data() + base,
             features.g.data() + base, features.b.data() + base);
  }
  return features;
}

PixelFeatures computeFeatures(const RgbdFrame& frame, const DaspConfig& config) {
  PixelFeatures features;
  computeFeatures(frame, config, features);
  return features;
}

void computeFeatures(const RgbdFrame& frame, const DaspConfig& config, PixelFeatures& features) {
  validateInput(frame, config);
  const int width = frame.color.cols;
  const int height = frame.color.rows;
  resizeFeatures(features, width, height, true);
  features.intrinsics = frame.intrinsics;
  const Intrinsics k = frame.intrinsics;
  const float inv_fx = 1.0f / k.fx;
  const float inv_fy = 1.0f / k.fy;

  // Pass 1: colour, depth and 3D points (eq. 3.4).
  const bool millimetres = frame.depth.type() == CV_16UC1;
  std::array<int, kFeatureChunks> chunk_valid{};
  detail::forChunks(
      height, kFeatureChunks, config.threads, [&](int chunk, int row_begin, int row_end) {
        for (int row = row_begin; row < row_end; ++row) {
          const float ray_y = (static_cast<float>(row) - k.cy) * inv_fy;
          const std::size_t base = static_cast<std::size_t>(row) * width;
          chunk_valid[static_cast<std::size_t>(chunk)] +=
              pointRow(frame.color.ptr<cv::Vec3b>(row),
                       millimetres ? frame.depth.ptr<std::uint16_t>(row) : nullptr,
                       millimetres ? nullptr : frame.depth.ptr<float>(row), width, inv_fx, k.cx,
                       ray_y, features.r.data() + base, features.g.data() + base,
                       features.b.data() + base, features.x.data() + base, features.y.data() + base,
                       features.z.data() + base, features.valid.data() + base);
        }
      });
  int valid_count = 0;
  for (int v : chunk_valid) valid_count += v;
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
  // across a depth jump is ignored and the one-sided difference is used (robust at edges). Near
  // the image border, neighbours outside the image count as invalid (scalar path).
  const int step = config.normal_step_px;
  const float jump = config.depth_jump_ratio;
  const NormalParams params{inv_fx, inv_fy, k.cx, config.experimental.max_slant_factor};
  const float* z_all = features.z.data();
  const auto depth_at = [&](int col, int row) {
    return col >= 0 && col < width && row >= 0 && row < height
               ? z_all[static_cast<std::size_t>(row) * width + col]
               : 0.0f;
  };
  detail::forChunks(height, kFeatureChunks, config.threads, [&](int, int row_begin, int row_end) {
    for (int row = row_begin; row < row_end; ++row) {
      const float ray_y = (static_cast<float>(row) - k.cy) * inv_fy;
      const std::size_t base = static_cast<std::size_t>(row) * width;
      float* nx = features.nx.data() + base;
      float* ny = features.ny.data() + base;
      float* nz = features.nz.data() + base;
      float* area = features.area.data() + base;
      const bool interior_row = row >= step && row + step < height;
      const int begin = interior_row ? std::min(step, width) : width;
      const int end = interior_row ? std::max(begin, width - step) : width;
      if (begin < end) {
        normalRowInterior(z_all + base, width, step, jump, ray_y, params, begin, end, nx, ny, nz,
                          area);
      }
      for (int col = 0; col < width; ++col) {
        if (col == begin && begin < end) col = end;
        if (col >= width) break;
        const float zc = z_all[base + col];
        const float h = static_cast<float>(step);
        const float dz_du =
            robustDerivative(depth_at(col - step, row), depth_at(col - 1, row), zc,
                             depth_at(col + 1, row), depth_at(col + step, row), h, jump);
        const float dz_dv =
            robustDerivative(depth_at(col, row - step), depth_at(col, row - 1), zc,
                             depth_at(col, row + 1), depth_at(col, row + step), h, jump);
        const float ray_x = (static_cast<float>(col) - k.cx) * inv_fx;
        normalAndArea(zc, dz_du, dz_dv, ray_x, ray_y, params, nx[col], ny[col], nz[col], area[col]);
      }
    }
  });
}

}  // namespace dasp

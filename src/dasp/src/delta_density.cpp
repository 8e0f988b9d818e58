// Delta Density Sampling (thesis §5.2.2, alg. 5).
#include "dasp/delta_density.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace dasp {
namespace {

constexpr float kPi = 3.14159265358979f;

void requireDensity(const cv::Mat& density) {
  if (density.empty() || density.type() != CV_32FC1) {
    throw std::invalid_argument("delta density sampling: density must be a non-empty CV_32FC1");
  }
  if (!cv::checkRange(density, true)) {
    throw std::invalid_argument("delta density sampling: density contains NaN or infinity");
  }
  double min_value = 0.0;
  cv::minMaxLoc(density, &min_value);
  if (min_value < 0.0) throw std::invalid_argument("delta density sampling: density must be >= 0");
}

bool pixelOf(const Seed& p, const cv::Mat& density, int& x, int& y) {
  x = static_cast<int>(std::lround(p.u));
  y = static_cast<int>(std::lround(p.v));
  return x >= 0 && y >= 0 && x < density.cols && y < density.rows && density.at<float>(y, x) > 0.0f;
}

// realizedDensity without the input checks (deltaDensitySampling checked them already).
cv::Mat realizedDensityUnchecked(const cv::Mat& density, const std::vector<Seed>& points,
                                 float kernel_cutoff_sigma) {
  cv::Mat valid;  // 1 where the density is positive, else 0: branch-free loops below
  cv::threshold(density, valid, 0.0, 1.0, cv::THRESH_BINARY);
  cv::Mat realized = cv::Mat::zeros(density.size(), CV_32FC1);
  std::vector<float> weight_x, weight_y;
  for (const Seed& p : points) {
    int px = 0, py = 0;
    if (!pixelOf(p, density, px, py)) continue;
    const float rho = density.at<float>(py, px);
    // K = rho exp(-pi rho d^2) = rho exp(-d^2 / (2 s^2)) with s^2 = 1 / (2 pi rho); separable
    // into a row and a column factor.
    const float sigma = 1.0f / std::sqrt(2.0f * kPi * rho);
    const int reach = std::max(1, static_cast<int>(std::ceil(kernel_cutoff_sigma * sigma)));
    const int x0 = std::max(0, px - reach), x1 = std::min(density.cols - 1, px + reach);
    const int y0 = std::max(0, py - reach), y1 = std::min(density.rows - 1, py + reach);
    weight_x.resize(static_cast<std::size_t>(x1 - x0 + 1));
    weight_y.resize(static_cast<std::size_t>(y1 - y0 + 1));
    for (int x = x0; x <= x1; ++x) {
      const float dx = static_cast<float>(x) - p.u;
      weight_x[static_cast<std::size_t>(x - x0)] = std::exp(-kPi * rho * dx * dx);
    }
    for (int y = y0; y <= y1; ++y) {
      const float dy = static_cast<float>(y) - p.v;
      weight_y[static_cast<std::size_t>(y - y0)] = std::exp(-kPi * rho * dy * dy);
    }
    double total = 0.0;  // kernel mass on pixels with density
    for (int y = y0; y <= y1; ++y) {
      const float* m = valid.ptr<float>(y);
      float row = 0.0f;
      for (int x = x0; x <= x1; ++x) row += m[x] * weight_x[static_cast<std::size_t>(x - x0)];
      total += static_cast<double>(row) * weight_y[static_cast<std::size_t>(y - y0)];
    }
    if (!(total > 0.0)) continue;
    const float scale = static_cast<float>(1.0 / total);  // unit mass over the valid pixels
    for (int y = y0; y <= y1; ++y) {
      const float* m = valid.ptr<float>(y);
      float* r = realized.ptr<float>(y);
      const float wy = weight_y[static_cast<std::size_t>(y - y0)] * scale;
      for (int x = x0; x <= x1; ++x) {
        r[x] += m[x] * weight_x[static_cast<std::size_t>(x - x0)] * wy;
      }
    }
  }
  return realized;
}

}  // namespace

cv::Mat realizedDensity(const cv::Mat& density, const std::vector<Seed>& points,
                        float kernel_cutoff_sigma) {
  requireDensity(density);
  if (!(kernel_cutoff_sigma > 0.0f)) {
    throw std::invalid_argument("realizedDensity: kernel_cutoff_sigma must be positive");
  }
  return realizedDensityUnchecked(density, points, kernel_cutoff_sigma);
}

NearestPointIndex::NearestPointIndex(const std::vector<Seed>& points, int width, int height,
                                     float cell_size_px)
    : points_(points), cell_size_(cell_size_px) {
  if (width <= 0 || height <= 0 || !(cell_size_px > 0.0f) || !std::isfinite(cell_size_px)) {
    throw std::invalid_argument("NearestPointIndex: image size and cell size must be positive");
  }
  cols_ = std::max(1, static_cast<int>(std::ceil(width / cell_size_px)));
  rows_ = std::max(1, static_cast<int>(std::ceil(height / cell_size_px)));
  buckets_.resize(static_cast<std::size_t>(cols_) * rows_);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int cx = cellOf(points[i].u, cols_), cy = cellOf(points[i].v, rows_);
    buckets_[static_cast<std::size_t>(cy) * cols_ + cx].push_back(static_cast<int>(i));
  }
  remaining_ = static_cast<int>(points.size());
}

int NearestPointIndex::cellOf(float coordinate, int cells) const {
  const int c = static_cast<int>(std::floor(coordinate / cell_size_));
  return std::clamp(c, 0, cells - 1);
}

int NearestPointIndex::removeNearest(float u, float v) {
  if (remaining_ == 0) return -1;
  const int cx = cellOf(u, cols_), cy = cellOf(v, rows_);
  float best_d2 = std::numeric_limits<float>::infinity();
  int best = -1;
  std::size_t best_bucket = 0, best_slot = 0;
  const int max_ring = std::max(cols_, rows_);
  for (int ring = 0; ring <= max_ring; ++ring) {
    // Every point in ring r is at least (r - 1) cells away: stop once that exceeds the best.
    if (best >= 0) {
      const float bound = static_cast<float>(ring - 1) * cell_size_;
      if (ring > 0 && bound * bound > best_d2) break;
    }
    for (int y = cy - ring; y <= cy + ring; ++y) {
      if (y < 0 || y >= rows_) continue;
      const bool edge_row = y == cy - ring || y == cy + ring;
      for (int x = cx - ring; x <= cx + ring; x += (edge_row ? 1 : 2 * ring)) {
        if (x >= 0 && x < cols_) {
          const std::size_t b = static_cast<std::size_t>(y) * cols_ + x;
          const std::vector<int>& bucket = buckets_[b];
          for (std::size_t s = 0; s < bucket.size(); ++s) {
            const Seed& p = points_[static_cast<std::size_t>(bucket[s])];
            const float du = p.u - u, dv = p.v - v;
            const float d2 = du * du + dv * dv;
            if (d2 < best_d2 || (d2 == best_d2 && bucket[s] < best)) {
              best_d2 = d2;
              best = bucket[s];
              best_bucket = b;
              best_slot = s;
            }
          }
        }
        if (ring == 0) break;
      }
    }
  }
  if (best < 0) return -1;
  std::vector<int>& bucket = buckets_[best_bucket];
  bucket[best_slot] = bucket.back();
  bucket.pop_back();
  --remaining_;
  return best;
}

DeltaDensityResult deltaDensitySampling(const cv::Mat& density, const std::vector<Seed>& points,
                                        const DeltaDensityConfig& config, std::uint64_t seed) {
  requireDensity(density);
  if (config.sampling == SeedingMethod::kGrid) {
    throw std::invalid_argument("delta density sampling: grid sampling ignores the delta mass");
  }
  if (!(config.smoothing_radius_multiple >= 0.0f) ||
      !std::isfinite(config.smoothing_radius_multiple)) {
    throw std::invalid_argument("delta density sampling: smoothing_radius_multiple must be >= 0");
  }
  DeltaDensityResult result;
  // Points whose pixel has no density any more (depth lost, left the image) end their strand.
  std::vector<Seed> live;
  std::vector<int> live_origin;
  live.reserve(points.size());
  live_origin.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    int x = 0, y = 0;
    if (pixelOf(points[i], density, x, y)) {
      live.push_back(points[i]);
      live_origin.push_back(static_cast<int>(i));
    } else {
      ++result.removed_invalid;
    }
  }

  if (!(config.kernel_cutoff_sigma > 0.0f)) {
    throw std::invalid_argument("delta density sampling: kernel_cutoff_sigma must be positive");
  }
  const cv::Mat realized = realizedDensityUnchecked(density, live, config.kernel_cutoff_sigma);
  cv::Mat delta = density - realized;  // eq. 5.4, zero where the density is zero
  const cv::Mat valid = density > 0.0f;
  const int valid_pixels = cv::countNonZero(valid);
  const double target_mass = cv::sum(density)[0];
  if (config.smoothing_radius_multiple > 0.0f && valid_pixels > 0 && target_mass > 0.0) {
    const double mean_rho = target_mass / valid_pixels;
    const double sigma = config.smoothing_radius_multiple / std::sqrt(kPi * mean_rho);
    // Normalised convolution over the valid pixels: smoothing does not leak mass into pixels
    // without density (which would make SPDS remove points at every depth border). It runs on
    // blocks of b x b pixels (mass sums) with sigma / b of about 2 blocks and is upsampled
    // bilinearly: sigma is several pixels, so this costs far less than a full-size blur.
    const int block = std::max(1, static_cast<int>(std::floor(sigma / 2.0)));
    const cv::Size coarse_size((density.cols + block - 1) / block,
                               (density.rows + block - 1) / block);
    cv::Mat padded_delta, padded_mask;
    cv::Mat mask_f;
    valid.convertTo(mask_f, CV_32F, 1.0 / 255.0);
    cv::copyMakeBorder(delta, padded_delta, 0, coarse_size.height * block - density.rows, 0,
                       coarse_size.width * block - density.cols, cv::BORDER_CONSTANT, 0.0);
    cv::copyMakeBorder(mask_f, padded_mask, 0, coarse_size.height * block - density.rows, 0,
                       coarse_size.width * block - density.cols, cv::BORDER_CONSTANT, 0.0);
    cv::Mat coarse_delta, coarse_mask;  // block means (mass / block^2; the factor cancels)
    cv::resize(padded_delta, coarse_delta, coarse_size, 0, 0, cv::INTER_AREA);
    cv::resize(padded_mask, coarse_mask, coarse_size, 0, 0, cv::INTER_AREA);
    const double coarse_sigma = sigma / block;
    cv::GaussianBlur(coarse_delta, coarse_delta, cv::Size(0, 0), coarse_sigma, coarse_sigma,
                     cv::BORDER_REFLECT);
    cv::GaussianBlur(coarse_mask, coarse_mask, cv::Size(0, 0), coarse_sigma, coarse_sigma,
                     cv::BORDER_REFLECT);
    cv::Mat coarse_smoothed;
    cv::divide(coarse_delta, cv::max(coarse_mask, 1e-6), coarse_smoothed);
    cv::Mat upsampled;
    cv::resize(coarse_smoothed, upsampled, padded_delta.size(), 0, 0, cv::INTER_LINEAR);
    cv::Mat smoothed = upsampled(cv::Rect(0, 0, density.cols, density.rows)).clone();
    smoothed.setTo(0.0f, ~valid);
    // Restore the exact integral of Delta rho (normalised convolution only nearly keeps it), so
    // that the expected point count stays integral(rho).
    const double correction = cv::sum(delta)[0] - cv::sum(smoothed)[0];
    smoothed += density * (correction / target_mass);
    delta = smoothed;
  }
  const cv::Mat positive = cv::max(delta, 0.0f);   // eq. 5.5
  const cv::Mat negative = cv::max(-delta, 0.0f);  // eq. 5.6
  result.positive_mass = cv::sum(positive)[0];
  result.negative_mass = cv::sum(negative)[0];

  // Remove points: the nearest remaining point to each sample of rho_-.
  std::vector<std::uint8_t> removed(live.size(), 0);
  if (!live.empty() && result.negative_mass > 0.0) {
    const std::vector<Seed> removals = sampleSeeds(negative, config.sampling, seed * 2 + 1);
    const double mean_rho = valid_pixels > 0 ? target_mass / valid_pixels : 0.0;
    const float spacing =
        mean_rho > 0.0 ? static_cast<float>(1.0 / std::sqrt(mean_rho)) : 16.0f;  // pixels
    NearestPointIndex index(live, density.cols, density.rows, std::max(2.0f, spacing));
    for (const Seed& r : removals) {
      const int nearest = index.removeNearest(r.u, r.v);
      if (nearest < 0) break;
      removed[static_cast<std::size_t>(nearest)] = 1;
      ++result.removed_by_density;
    }
  }
  for (std::size_t i = 0; i < live.size(); ++i) {
    if (removed[i]) continue;
    result.points.push_back(live[i]);
    result.origin.push_back(live_origin[i]);
  }
  // Add points: the samples of rho_+.
  if (result.positive_mass > 0.0) {
    const std::vector<Seed> additions = sampleSeeds(positive, config.sampling, seed * 2 + 2);
    for (const Seed& a : additions) {
      result.points.push_back(a);
      result.origin.push_back(-1);
    }
    result.added = static_cast<int>(additions.size());
  }
  return result;
}

}  // namespace dasp

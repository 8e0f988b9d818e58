// One-call entry points: DASP (alg. 4), ASP_RGB and ASP_RGBD.
#include "dasp/dasp.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "dasp/connectivity.h"
#include "dasp/dalic.h"
#include "dasp/density.h"
#include "dasp/features.h"
#include "dasp/sampling.h"
#include "dasp/superpoints.h"

namespace dasp {
namespace {

// The steps after the density, with the sampling, iteration and connectivity settings of
// `config` (DaspConfig or AspConfig): seeds, DALIC iterations, connectivity and the superpoint
// fit (radius and depth exponent of the superpixels: dalic.params()). `dalic` refers to
// `features` and `density` and has been reset to the run's parameters. depth_jump_ratio > 0:
// connectivity on the surface (DASP), 0: in the image (the ASP baselines).
template <class Config>
Superpixels cluster(Dalic& dalic, const PixelFeatures& features, const cv::Mat& density,
                    const Config& config, float depth_jump_ratio) {
  std::vector<Seed> seeds = sampleSeeds(density, config.seeding, config.seed);
  if (seeds.empty()) {  // density too low for even one point: one superpixel at its maximum
    cv::Point max_location;
    cv::minMaxLoc(density, nullptr, nullptr, nullptr, &max_location);
    seeds.push_back({static_cast<float>(max_location.x), static_cast<float>(max_location.y)});
  }
  dalic.initialize(seeds);
  for (int it = 0; it < config.iterations; ++it) {
    dalic.assign();
    if (it + 1 < config.iterations) dalic.update();
  }
  Superpixels result;
  result.labels = dalic.labels().clone();
  const cv::Mat valid(features.height, features.width, CV_8UC1,
                      const_cast<std::uint8_t*>(features.valid.data()));
  // Without connectivity enforcement only empty labels are dropped, so that labels stay dense
  // indices into the superpixel vector. With it, a superpixel whose largest piece holds less
  // than min_size_fraction of one superpixel's density mass is purged (as during DALIC).
  if (config.enforce_connectivity) {
    cv::Mat depth;  // surface connectivity for the RGB-D methods (see enforceConnectivity)
    if (features.hasDepth() && depth_jump_ratio > 0.0f) {
      depth =
          cv::Mat(features.height, features.width, CV_32FC1, const_cast<float*>(features.z.data()));
    }
    enforceConnectivity(result.labels, valid, density, config.min_size_fraction, depth,
                        depth_jump_ratio);
  } else {
    std::vector<int> renumber(dalic.clusters().size(), -1);
    int next = 0;
    for (int row = 0; row < result.labels.rows; ++row) {
      int* l = result.labels.ptr<int>(row);
      for (int col = 0; col < result.labels.cols; ++col) {
        if (l[col] < 0) continue;
        int& mapped = renumber[static_cast<std::size_t>(l[col])];
        if (mapped < 0) mapped = next++;
        l[col] = mapped;
      }
    }
  }
  const DalicParams& params = dalic.params();
  result.superpixels =
      fitSuperpoints(result.labels, features, density, params.radius_m, params.depth_exponent);
  return result;
}

}  // namespace

struct DaspSegmenter::Buffers {
  PixelFeatures features;
  cv::Mat density;
  std::optional<Dalic> dalic;  // refers to features and density
};

DaspSegmenter::DaspSegmenter(const DaspConfig& config)
    : config_(config), buffers_(std::make_unique<Buffers>()) {}

DaspSegmenter::~DaspSegmenter() = default;

Superpixels DaspSegmenter::compute(const RgbdFrame& frame) {
  Buffers& b = *buffers_;
  computeFeatures(frame, config_, b.features);  // validates
  const float radius = daspRadius(b.features, config_);
  computeDepthDensity(b.features, radius, b.density, config_.experimental.depth_exponent);
  const DalicParams params =
      dalicParams(config_, MetricKind::kDepthAdaptive, radius,
                  config_.size_mode == SizeMode::kCount ? config_.superpixel_count : 0);
  if (b.dalic) {
    b.dalic->reset(params);
  } else {
    b.dalic.emplace(b.features, b.density, params);
  }
  return cluster(*b.dalic, b.features, b.density, config_, config_.depth_jump_ratio);
}

Superpixels computeDasp(const RgbdFrame& frame, const DaspConfig& config) {
  // Fresh buffers would cost more than the clustering: each call would page in 17 MB again.
  thread_local DaspSegmenter segmenter;
  segmenter.setConfig(config);
  return segmenter.compute(frame);
}

Superpixels computeAspRgb(const cv::Mat& color, const AspConfig& config) {
  const PixelFeatures features = computeColorFeatures(color);  // checks the image type
  const long long pixels = static_cast<long long>(features.size());
  if (config.superpixel_count < 1 || config.superpixel_count > pixels) {
    throw std::invalid_argument("ASP: superpixel_count must be in [1, pixel count " +
                                std::to_string(pixels) + "], got " +
                                std::to_string(config.superpixel_count));
  }
  if (config.iterations < 1) throw std::invalid_argument("ASP: iterations must be >= 1");
  if (!(config.weight_spatial >= 0.0f) || !(config.weight_color >= 0.0f) ||
      !std::isfinite(config.weight_spatial) || !std::isfinite(config.weight_color)) {
    throw std::invalid_argument("ASP: metric weights must be finite and >= 0");
  }
  if (!(config.window_multiple > 0.0f) || !std::isfinite(config.window_multiple)) {
    throw std::invalid_argument("ASP: window_multiple must be finite and positive");
  }
  if (!(config.min_size_fraction >= 0.0f) || !(config.min_size_fraction < 1.0f)) {
    throw std::invalid_argument("ASP: min_size_fraction must be in [0, 1)");
  }
  if (config.threads < 0) throw std::invalid_argument("ASP: threads must be >= 0");
  cv::Mat density;
  if (config.density.empty()) {
    density = computeConstantDensity(features, config.superpixel_count);
  } else {
    if (config.density.type() != CV_32FC1 || config.density.size() != color.size()) {
      throw std::invalid_argument("ASP: user density must be CV_32FC1 of the image size");
    }
    if (!cv::checkRange(config.density, true)) {
      throw std::invalid_argument("ASP: user density contains NaN or infinity");
    }
    double min_value = 0.0;
    cv::minMaxLoc(config.density, &min_value);
    if (min_value < 0.0) throw std::invalid_argument("ASP: user density must be >= 0");
    const double integral = densityIntegral(config.density);
    if (!(integral > 0.0)) throw std::invalid_argument("ASP: user density integrates to 0");
    density = config.density * (config.superpixel_count / integral);  // eq. 3.17
    if (!density.isContinuous()) density = density.clone();
  }
  Dalic dalic(features, density, dalicParams(config));
  return cluster(dalic, features, density, config, 0.0f);
}

Superpixels computeAspRgbd(const RgbdFrame& frame, const DaspConfig& config) {
  DaspConfig count_config = config;
  count_config.size_mode = SizeMode::kCount;
  const PixelFeatures features = computeFeatures(frame, count_config);  // validates
  const float radius = radiusForCount(features, config.superpixel_count);
  const cv::Mat density = computeConstantDensity(features, config.superpixel_count);
  Dalic dalic(features, density,
              dalicParams(config, MetricKind::kColorDepth2D, radius, config.superpixel_count));
  return cluster(dalic, features, density, config, 0.0f);
}

}  // namespace dasp

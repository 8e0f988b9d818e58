// One-call entry points: DASP (alg. 4), ASP_RGB and ASP_RGBD.
#include "dasp/dasp.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "dasp/stages.h"

namespace dasp {
namespace {

struct RunParams {
  SeedingMethod seeding;
  std::uint64_t seed;
  int iterations;
  bool enforce_connectivity;
  float min_size_fraction;
  float depth_jump_ratio;       // > 0: connectivity on the surface (RGB-D methods), 0: in the image
  float depth_exponent = 2.0f;  // DASP's density exponent: the superpixels' radius_m (fit)
};

// SPDS/grid/random seeds, DALIC iterations, connectivity and the superpoint fit.
// `dalic` refers to `features` and `density` and has been reset to the run's parameters.
Superpixels cluster(Dalic& dalic, const PixelFeatures& features, const cv::Mat& density,
                    float radius_m, const RunParams& run) {
  std::vector<Seed> seeds = sampleSeeds(density, run.seeding, run.seed);
  if (seeds.empty()) {  // density too low for even one point: one superpixel at its maximum
    cv::Point max_location;
    cv::minMaxLoc(density, nullptr, nullptr, nullptr, &max_location);
    seeds.push_back({static_cast<float>(max_location.x), static_cast<float>(max_location.y)});
  }
  dalic.initialize(seeds);
  for (int it = 0; it < run.iterations; ++it) {
    dalic.assign();
    if (it + 1 < run.iterations) dalic.update();
  }
  Superpixels result;
  result.labels = dalic.labels().clone();
  const cv::Mat valid(features.height, features.width, CV_8UC1,
                      const_cast<std::uint8_t*>(features.valid.data()));
  // Without connectivity enforcement only empty labels are dropped, so that labels stay dense
  // indices into the superpixel vector. With it, a superpixel whose largest piece holds less
  // than min_size_fraction of one superpixel's density mass is purged (as during DALIC).
  if (run.enforce_connectivity) {
    cv::Mat depth;  // surface connectivity for the RGB-D methods (see enforceConnectivity)
    if (features.hasDepth() && run.depth_jump_ratio > 0.0f) {
      depth =
          cv::Mat(features.height, features.width, CV_32FC1, const_cast<float*>(features.z.data()));
    }
    enforceConnectivity(result.labels, valid, density, run.min_size_fraction, depth,
                        run.depth_jump_ratio);
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
  result.superpixels =
      fitSuperpoints(result.labels, features, density, radius_m, run.depth_exponent);
  return result;
}

Superpixels cluster(const PixelFeatures& features, const cv::Mat& density,
                    const DalicParams& dalic_params, const RunParams& run) {
  Dalic dalic(features, density, dalic_params);
  return cluster(dalic, features, density, dalic_params.radius_m, run);
}

}  // namespace

float daspRadius(const PixelFeatures& features, const DaspConfig& config) {
  return config.size_mode == SizeMode::kCount
             ? radiusForCount(features, config.superpixel_count, config.depth_exponent)
             : config.radius_m;
}

DalicParams dalicParams(const DaspConfig& config, MetricKind metric, float radius_m,
                        int target_count) {
  DalicParams params;
  params.metric = metric;
  params.weight_spatial = config.weight_spatial;
  params.weight_color = config.weight_color;
  params.weight_normal = config.weight_normal;
  params.weight_depth = config.weight_depth;
  params.window_multiple = config.window_multiple;
  params.radius_m = radius_m;
  params.depth_exponent = metric == MetricKind::kDepthAdaptive ? config.depth_exponent : 2.0f;
  params.min_size_fraction = config.min_size_fraction;
  params.target_count = target_count;
  params.threads = config.threads;
  return params;
}

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
  computeDepthDensity(b.features, radius, b.density, config_.depth_exponent);
  const DalicParams params =
      dalicParams(config_, MetricKind::kDepthAdaptive, radius,
                  config_.size_mode == SizeMode::kCount ? config_.superpixel_count : 0);
  if (b.dalic) {
    b.dalic->reset(params);
  } else {
    b.dalic.emplace(b.features, b.density, params);
  }
  return cluster(*b.dalic, b.features, b.density, radius,
                 {config_.seeding, config_.seed, config_.iterations, config_.enforce_connectivity,
                  config_.min_size_fraction, config_.depth_jump_ratio, config_.depth_exponent});
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
  DalicParams params;
  params.metric = MetricKind::kColor2D;
  params.weight_spatial = config.weight_spatial;
  params.weight_color = config.weight_color;
  params.window_multiple = config.window_multiple;
  params.min_size_fraction = config.min_size_fraction;
  params.target_count = config.superpixel_count;
  params.threads = config.threads;
  return cluster(features, density, params,
                 {config.seeding, config.seed, config.iterations, config.enforce_connectivity,
                  config.min_size_fraction, 0.0f});
}

Superpixels computeAspRgbd(const RgbdFrame& frame, const DaspConfig& config) {
  DaspConfig count_config = config;
  count_config.size_mode = SizeMode::kCount;
  const PixelFeatures features = computeFeatures(frame, count_config);  // validates
  const float radius = radiusForCount(features, config.superpixel_count);
  const cv::Mat density = computeConstantDensity(features, config.superpixel_count);
  const DalicParams params =
      dalicParams(config, MetricKind::kColorDepth2D, radius, config.superpixel_count);
  return cluster(features, density, params,
                 {config.seeding, config.seed, config.iterations, config.enforce_connectivity,
                  config.min_size_fraction, 0.0f});
}

}  // namespace dasp

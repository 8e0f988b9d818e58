// s-DASP (thesis ch. 4): ultrametric contour graph, cut threshold, segments.
#include "dasp/sdasp.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "dasp/segmentation.h"

namespace dasp {

WeightedGraph ultrametricContourGraph(const Superpixels& superpixels, const SdaspConfig& config) {
  WeightedGraph ucg = buildSuperpixelGraph(superpixels, config.graph);
  const std::vector<float> global = globalizeEdgeWeights(ucg, config.spectral);
  for (std::size_t k = 0; k < ucg.edges.size(); ++k) ucg.edges[k].weight = global[k];
  return ucg;
}

float adaptiveCutThreshold(const WeightedGraph& ucg, float scale, float quantile,
                           float max_threshold) {
  if (!(scale > 0.0f) || !std::isfinite(scale)) {
    throw std::invalid_argument("adaptiveCutThreshold: scale must be a positive number");
  }
  if (!(quantile >= 0.0f && quantile <= 1.0f)) {
    throw std::invalid_argument("adaptiveCutThreshold: quantile must lie in [0, 1]");
  }
  if (!(max_threshold > 0.0f)) {
    throw std::invalid_argument("adaptiveCutThreshold: max_threshold must be positive");
  }
  const std::vector<float> levels = spanningMergeLevels(ucg);
  if (levels.empty()) return max_threshold;
  const double position = static_cast<double>(quantile) * static_cast<double>(levels.size() - 1);
  const std::size_t below = static_cast<std::size_t>(position);
  const std::size_t above = std::min(below + 1, levels.size() - 1);
  const double fraction = position - static_cast<double>(below);
  const double q = (1.0 - fraction) * levels[below] + fraction * levels[above];
  return static_cast<float>(std::min<double>(max_threshold, scale * q));
}

float cutThreshold(const WeightedGraph& ucg, const SdaspConfig& config) {
  if (config.cut == CutRule::kAdaptive) {
    return adaptiveCutThreshold(ucg, config.adaptive_scale, config.adaptive_quantile,
                                config.adaptive_max_threshold);
  }
  if (!std::isfinite(config.threshold)) {
    throw std::invalid_argument("cutThreshold: threshold must be finite");
  }
  return config.threshold;
}

SdaspSegmentation computeSdasp(const Superpixels& superpixels, const SdaspConfig& config) {
  SdaspSegmentation s;
  s.ucg = ultrametricContourGraph(superpixels, config);
  s.threshold = cutThreshold(s.ucg, config);
  s.node_segments = segmentGraph(s.ucg, s.threshold);
  s.segments = segmentPixels(superpixels.labels, s.node_segments);
  return s;
}

}  // namespace dasp

// s-DASP image segmentation (thesis ch. 4): the ultrametric contour graph of a frame's
// superpixels (neighbourhood graph, spectral globalisation) cut at a per-frame threshold.
// Entry point: computeSdasp; the graph segmentation itself is in dasp/segmentation.h.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "dasp/dasp.h"
#include "dasp/spectral.h"
#include "dasp/superpixel_graph.h"

namespace dasp {

/// How s-DASP picks the cut threshold of a frame.
enum class CutRule {
  kGlobal,    ///< the same SdaspConfig::threshold on every frame
  kAdaptive,  ///< from the frame's own merge levels (adaptiveCutThreshold)
};

/// The superpixel graph of s-DASP: SuperpixelGraphConfig with heavier colour and normal terms
/// (lambda_c 4, lambda_n 8; eq. 4.17-4.21), chosen by 5-fold cross-validation over the 45 OSD
/// learn frames among the settings with lambda_c >= 4 (with 2 the colour edges of thin objects
/// and touching boxes are lost, test/sdasp_test.cpp); docs/results/sdasp.md. The defaults of
/// SuperpixelGraphConfig itself (Dasp's published graph, t-DASP) stay.
inline SuperpixelGraphConfig sdaspGraphDefaults() {
  SuperpixelGraphConfig graph;
  graph.weight_color = 4.0f;
  graph.weight_normal = 8.0f;
  return graph;
}

/// All s-DASP parameters after the superpixels. The thesis leaves the cut free (§4.3.3); the
/// numbers below were chosen by cross-validation over the OSD learn split (docs/results/sdasp.md).
struct SdaspConfig {
  SuperpixelGraphConfig graph = sdaspGraphDefaults();
  SpectralConfig spectral;
  /// Rule for the cut threshold of a frame (cutThreshold).
  CutRule cut = CutRule::kAdaptive;
  /// kGlobal: cut threshold on the normalised UCG weights [1], the cross-validated ODS threshold.
  float threshold = 0.09f;
  /// kAdaptive: threshold = min(adaptive_max_threshold, adaptive_scale * the adaptive_quantile
  /// quantile of the frame's merge levels) [1]; see adaptiveCutThreshold. > 0.
  float adaptive_scale = 6.0f;
  /// kAdaptive: quantile in [0, 1] of the merge levels (0.75: the upper quartile).
  float adaptive_quantile = 0.75f;
  /// kAdaptive: upper bound of the threshold [1] (frames with few weak edges). > 0.
  float adaptive_max_threshold = 0.15f;
};

/// The per-frame cut threshold of CutRule::kAdaptive: min(max_threshold, scale * q) with q the
/// `quantile` quantile (linear interpolation) of spanningMergeLevels(ucg); max_threshold for a
/// graph without edges. Throws std::invalid_argument for scale <= 0, max_threshold <= 0 or a
/// quantile outside [0, 1].
float adaptiveCutThreshold(const WeightedGraph& ucg, float scale, float quantile,
                           float max_threshold);

/// The cut threshold of `ucg` under config.cut: config.threshold (kGlobal) or
/// adaptiveCutThreshold with the config's adaptive_* fields (kAdaptive). Throws
/// std::invalid_argument as adaptiveCutThreshold, or for a non-finite threshold.
float cutThreshold(const WeightedGraph& ucg, const SdaspConfig& config);

/// The ultrametric contour graph of a superpixel result: neighbourhood graph, then globalised
/// weights (edge weight = boundary strength, [0, 1] with the default normalisation).
WeightedGraph ultrametricContourGraph(const Superpixels& superpixels,
                                      const SdaspConfig& config = {});

/// s-DASP of one frame: its ultrametric contour graph, cut threshold and segments.
struct SdaspSegmentation {
  WeightedGraph ucg;               ///< ultrametricContourGraph(superpixels, config)
  float threshold = 0.0f;          ///< cutThreshold(ucg, config)
  std::vector<int> node_segments;  ///< segmentGraph(ucg, threshold): segment per superpixel
  cv::Mat segments;                ///< segment per pixel, CV_32SC1, -1 where no superpixel is
};

/// s-DASP (§4.3) of a superpixel result; throws std::invalid_argument as the steps do.
SdaspSegmentation computeSdasp(const Superpixels& superpixels, const SdaspConfig& config = {});

}  // namespace dasp

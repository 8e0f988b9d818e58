// s-DASP segmentation of the ultrametric contour graph (thesis §4.3.3): thresholding the
// globalised boundary weights and taking connected components, for one threshold or a whole sweep
// in one pass, the pixel ultrametric contour map (UCM) and boundary precision/recall curves that
// agree exactly with metrics::boundaryScores of the per-threshold segmentation.
//
// Threshold convention: at threshold t the superpixels joined by an edge of weight < t are merged
// (connected components); an edge of weight >= t stays a boundary. t <= 0 keeps every superpixel
// apart, t above the largest weight merges every connected component.
#pragma once

#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>

#include "dasp/dasp.h"
#include "dasp/metrics.h"
#include "dasp/spectral.h"
#include "dasp/superpixel_graph.h"

namespace dasp {

/// Segment id of every node (0..segments-1, numbered by the smallest node of each segment) after
/// merging the edges of weight < threshold.
std::vector<int> segmentGraph(const WeightedGraph& graph, float threshold);

/// segmentGraph for every threshold of `thresholds` (any order) in one pass over the edges sorted
/// by weight (union-find). Result[i] belongs to thresholds[i].
std::vector<std::vector<int>> segmentGraphSweep(const WeightedGraph& graph,
                                                const std::vector<float>& thresholds);

/// Pixel segmentation: label of pixel = node_segments[superpixel label]; pixels with a negative
/// label stay -1. Throws std::invalid_argument for a label outside node_segments.
cv::Mat segmentPixels(const cv::Mat& superpixel_labels, const std::vector<int>& node_segments);

/// Merge level of every pair of superpixels adjacent in the label image: the smallest threshold
/// at which they lie in one segment, i.e. the minimax edge weight over all paths (the ultrametric),
/// +infinity when no path joins them. Edges (a < b) sorted by (a, b), weight = merge level.
WeightedGraph mergeLevels(const cv::Mat& superpixel_labels, const WeightedGraph& ucg);

/// Pixel ultrametric contour map (CV_32FC1) over `mask` (CV_8UC1 or empty = all): at a pixel p,
/// the largest merge level between p's segment and a 4-neighbour in the mask with another
/// superpixel label (+infinity if one of the two is unlabelled), -1 where p has no such neighbour.
/// Pixels outside the mask are -1. By construction (ucm >= t) is exactly
/// metrics::boundaryMap(segmentPixels(labels, segmentGraph(ucg, t)), mask) for every t > -1.
cv::Mat ultrametricContourMap(const cv::Mat& superpixel_labels, const WeightedGraph& ucg,
                              const cv::Mat& mask = cv::Mat());

/// Boundary matching counts of one segmentation (or one threshold) against a reference, the
/// numbers behind metrics::BoundaryScores; counts of several images add up (ODS).
struct BoundaryCounts {
  double threshold = 0.0;
  std::size_t partition_pixels = 0;  ///< |B(P)|
  std::size_t precise_pixels = 0;    ///< of those, matched by a reference boundary pixel
  std::size_t reference_pixels = 0;  ///< |B(X)|
  std::size_t recalled_pixels = 0;   ///< of those, matched by a partition boundary pixel
  double precision() const;          ///< 1 when there is no partition boundary (as metrics.h)
  double recall() const;             ///< 1 when there is no reference boundary
  double f1() const;
  BoundaryCounts& operator+=(const BoundaryCounts& other);
};

/// Boundary counts of the segmentations (ucm >= t) for every t of `thresholds`, in one pass over
/// the pixels: precision and recall equal metrics::boundaryScores(segmentation at t,
/// ground_truth, mask, tolerance_px). ucm from ultrametricContourMap with the same mask.
std::vector<BoundaryCounts> boundaryCurve(const cv::Mat& ucm, const cv::Mat& ground_truth,
                                          const cv::Mat& mask, const std::vector<float>& thresholds,
                                          int tolerance_px = metrics::kDefaultBoundaryTolerancePx);

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

/// Merge levels of a graph in ascending order: the weights of the edges of its minimum spanning
/// forest (Kruskal), i.e. the levels at which the segments of segmentGraphSweep join.
std::vector<float> spanningMergeLevels(const WeightedGraph& graph);

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

}  // namespace dasp

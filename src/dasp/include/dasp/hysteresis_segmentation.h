// Semi-Supervised Hysteresis Segmentation (thesis §5.4.5): segments a boundary-weighted graph
// (e.g. the globalised strand graph) by merging edges in ascending weight under three thresholds
// that depend on the labels the nodes carried in the previous frame, then gives each connected
// component the most frequent previous label it contains, so that labels persist over time.
#pragma once

#include <cstdint>
#include <vector>

#include "dasp/superpixel_graph.h"

namespace dasp {

/// The three thresholds t_force < t_normal < t_grant on the boundary weights (globalised weights
/// normalised to [0, 1] by their maximum, GlobalWeightNormalization::kMax). An edge merges when
/// its weight is below the threshold of its case (the s-DASP convention of segmentGraph; the
/// thesis writes <=). The thesis gives no values: t_normal is the s-DASP threshold
/// (SdaspConfig::threshold, chosen on the OSD learn split), the other two a band of a factor 2
/// around it.
struct HysteresisConfig {
  /// Forced merge: any two nodes, even with different supervised labels (low confidence).
  float force = 0.075f;
  /// Normal merge: at least one of the two labels is not supervised (medium confidence).
  float normal = 0.15f;
  /// Granted merge: both labels supervised and identical (high confidence).
  float grant = 0.3f;
};

/// Result of one hysteresis segmentation.
struct HysteresisResult {
  std::vector<std::int64_t> labels;  ///< per node, >= 0
  int component_count = 0;
  int labels_continued = 0;  ///< components that kept a supervised label
  int labels_created = 0;    ///< components that got a new label
};

/// Segments `boundary_graph` (edge weight = boundary strength, smaller = more similar).
/// The three merge rules look at the labels of the segments merged so far (a segment is
/// supervised by the heaviest previous label it holds), as eq. 5.19 does.
/// supervised[i]: label of node i in the previous frame (>= 0) or -1 (not supervised: new node).
/// node_size: size used to order the components (e.g. pixels), empty = every node counts 1.
/// New labels are taken from next_label, which is advanced. Throws std::invalid_argument when
/// the sizes do not match, edges are out of range, or the thresholds are not ordered.
HysteresisResult hysteresisSegmentation(const WeightedGraph& boundary_graph,
                                        const std::vector<std::int64_t>& supervised,
                                        const std::vector<double>& node_size,
                                        const HysteresisConfig& config, std::int64_t& next_label);

}  // namespace dasp

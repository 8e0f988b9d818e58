// Superpixel neighbourhood graph of s-DASP (thesis §4.3.1): one node per superpixel, an edge
// between superpixels that share a border of more than Theta pixel pairs on the 4-neighbour pixel
// lattice (eq. 4.16), weighted by the similarity W = exp(-d_S) (eq. 4.17-4.21).
#pragma once

#include <vector>

#include "dasp/dasp.h"

namespace dasp {

/// An undirected edge between nodes a < b with a weight in [0, 1] (similarity graphs) or >= 0
/// (boundary strength graphs such as the ultrametric contour graph).
struct GraphEdge {
  int a = -1;
  int b = -1;
  float weight = 0.0f;
};

/// A weighted undirected graph with nodes 0..node_count-1 and no duplicate edges.
struct WeightedGraph {
  int node_count = 0;
  std::vector<GraphEdge> edges;
};

/// Parameters of the superpixel neighbourhood graph and of the superpixel distance d_S (s-DASP,
/// §4.3.1): d_S = weight_position d_v + weight_normal d_n + weight_color d_c (eq. 4.17) with
/// d_c = |c1 - c2| (RGB in [0, 1], eq. 4.19), d_v = max(0, |v1 - v2| - 2R) / 2R (eq. 4.20, R in
/// metres), d_n = max(0, (n2 - n1) . (v1 - v2) / |v1 - v2|) (eq. 4.21, concave edges only). The
/// thesis gives no values; defaults from grids on the OSD learn split (docs/results/sdasp.md).
/// Normal sign convention and the grids: docs/dasp_core.md#superpixel-distance
struct SuperpixelGraphConfig {
  /// Theta of eq. 4.16: two superpixels are neighbours when more than this many 4-neighbour pixel
  /// pairs (p, q), p in one and q in the other, exist. >= 0.
  int min_border_pairs = 4;
  float weight_color = 2.0f;     ///< lambda_c, per unit of RGB distance. >= 0.
  float weight_position = 2.0f;  ///< lambda_v, per unit of (excess distance / 2R). >= 0.
  float weight_normal = 4.0f;    ///< lambda_n, per unit of the concave normal term. >= 0.
  /// Radius R in metres for eq. 4.20. 0: the mean of the two superpixels' radius_m. When R is 0
  /// (colour-only superpixels such as ASP_RGB) the position and normal terms are left out.
  float radius_m = 0.0f;
};

/// d_S(a, b) of eq. 4.17 (a distance >= 0, 0 for identical superpixels); the edge weight is
/// W = exp(-d_S). Exposed so that t-DASP strand weights use the same similarity. Throws
/// std::invalid_argument for negative weights or radius.
float superpixelSimilarity(const Superpixel& a, const Superpixel& b,
                           const SuperpixelGraphConfig& config);

/// Neighbour graph of a superpixel result (DASP or any other method that fills
/// Superpixels::superpixels in label order): edge when two superpixels share more than Theta
/// border pixel pairs, weight W = exp(-d_S) in (0, 1]. Edges are sorted by (a, b).
/// node_count = superpixels.superpixels.size(). Throws std::invalid_argument when the label image
/// is not CV_32SC1 or holds a label >= node_count, or for an invalid config.
WeightedGraph buildSuperpixelGraph(const Superpixels& superpixels,
                                   const SuperpixelGraphConfig& config = {});

/// Number of 4-neighbour pixel pairs between every two adjacent labels >= 0 of a CV_32SC1 label
/// image (labels < 0 ignored), as edges (a < b) whose weight is the pair count; sorted by (a, b).
WeightedGraph labelAdjacency(const cv::Mat& labels, int label_count);

}  // namespace dasp

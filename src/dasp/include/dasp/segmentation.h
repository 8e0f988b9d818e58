// Segmentation of a boundary-weighted superpixel graph (s-DASP, thesis §4.3.3; generic over the
// graph): connected components below a threshold, for one threshold or a whole sweep in one
// pass, the merge levels and the pixel ultrametric contour map (UCM).
//
// Threshold convention: at threshold t the superpixels joined by an edge of weight < t are merged
// (connected components); an edge of weight >= t stays a boundary. t <= 0 keeps every superpixel
// apart, t above the largest weight merges every connected component.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

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

/// Merge levels of a graph in ascending order: the weights of the edges of its minimum spanning
/// forest (Kruskal), i.e. the levels at which the segments of segmentGraphSweep join.
std::vector<float> spanningMergeLevels(const WeightedGraph& graph);

}  // namespace dasp

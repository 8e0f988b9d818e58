// Threshold segmentation of a boundary-weighted graph, merge levels and the pixel UCM.
#include "dasp/segmentation.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

namespace dasp {
namespace {

constexpr float kNoBoundary = -1.0f;

class UnionFind {
 public:
  explicit UnionFind(int n) : parent_(static_cast<std::size_t>(n)) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  int find(int i) {
    while (parent_[i] != i) {
      parent_[i] = parent_[parent_[i]];
      i = parent_[i];
    }
    return i;
  }
  /// Joins the sets of a and b; returns false when they were already one.
  bool unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a == b) return false;
    parent_[std::max(a, b)] = std::min(a, b);
    return true;
  }

 private:
  std::vector<int> parent_;
};

void checkGraph(const WeightedGraph& graph, const char* what) {
  if (graph.node_count < 0) {
    throw std::invalid_argument(std::string(what) + ": negative node_count");
  }
  for (const GraphEdge& e : graph.edges) {
    if (e.a < 0 || e.b < 0 || e.a >= graph.node_count || e.b >= graph.node_count) {
      throw std::invalid_argument(std::string(what) + ": edge out of range");
    }
  }
}

void checkLabels(const cv::Mat& labels, int node_count, const char* what) {
  if (labels.type() != CV_32SC1) {
    throw std::invalid_argument(std::string(what) + ": superpixel labels must be CV_32SC1");
  }
  double max_label = -1.0;
  if (!labels.empty()) cv::minMaxLoc(labels, nullptr, &max_label);
  if (max_label >= node_count) {
    throw std::invalid_argument(std::string(what) + ": label " +
                                std::to_string(static_cast<int>(max_label)) +
                                " has no node in the graph");
  }
}

void checkMask(const cv::Mat& mask, const cv::Size& size, const char* what) {
  if (!mask.empty() && (mask.type() != CV_8UC1 || mask.size() != size)) {
    throw std::invalid_argument(std::string(what) + ": mask must be CV_8UC1 of the image size");
  }
}

std::vector<std::size_t> edgesByWeight(const WeightedGraph& graph) {
  std::vector<std::size_t> order(graph.edges.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t l, std::size_t r) {
    return graph.edges[l].weight < graph.edges[r].weight;
  });
  return order;
}

std::vector<int> numberSegments(UnionFind& sets, int n) {
  std::vector<int> segment(static_cast<std::size_t>(n), -1);
  std::vector<int> id_of_root(static_cast<std::size_t>(n), -1);
  int next = 0;
  for (int i = 0; i < n; ++i) {
    const int root = sets.find(i);
    if (id_of_root[root] < 0) id_of_root[root] = next++;
    segment[i] = id_of_root[root];
  }
  return segment;
}

}  // namespace

std::vector<int> segmentGraph(const WeightedGraph& graph, float threshold) {
  return segmentGraphSweep(graph, {threshold}).front();
}

std::vector<std::vector<int>> segmentGraphSweep(const WeightedGraph& graph,
                                                const std::vector<float>& thresholds) {
  checkGraph(graph, "segmentGraphSweep");
  std::vector<std::size_t> threshold_order(thresholds.size());
  std::iota(threshold_order.begin(), threshold_order.end(), 0);
  std::stable_sort(threshold_order.begin(), threshold_order.end(),
                   [&](std::size_t l, std::size_t r) { return thresholds[l] < thresholds[r]; });
  const std::vector<std::size_t> edge_order = edgesByWeight(graph);
  UnionFind sets(graph.node_count);
  std::vector<std::vector<int>> result(thresholds.size());
  std::size_t next_edge = 0;
  for (const std::size_t t : threshold_order) {
    while (next_edge < edge_order.size() &&
           graph.edges[edge_order[next_edge]].weight < thresholds[t]) {
      const GraphEdge& e = graph.edges[edge_order[next_edge]];
      sets.unite(e.a, e.b);
      ++next_edge;
    }
    result[t] = numberSegments(sets, graph.node_count);
  }
  return result;
}

cv::Mat segmentPixels(const cv::Mat& superpixel_labels, const std::vector<int>& node_segments) {
  checkLabels(superpixel_labels, static_cast<int>(node_segments.size()), "segmentPixels");
  cv::Mat segments(superpixel_labels.size(), CV_32SC1);
  for (int y = 0; y < segments.rows; ++y) {
    const int* in = superpixel_labels.ptr<int>(y);
    int* out = segments.ptr<int>(y);
    for (int x = 0; x < segments.cols; ++x) out[x] = in[x] < 0 ? -1 : node_segments[in[x]];
  }
  return segments;
}

WeightedGraph mergeLevels(const cv::Mat& superpixel_labels, const WeightedGraph& ucg) {
  checkGraph(ucg, "mergeLevels");
  checkLabels(superpixel_labels, ucg.node_count, "mergeLevels");
  const int n = ucg.node_count;
  // Merge tree (dendrogram) of Kruskal's algorithm: leaves 0..n-1, every union adds a node whose
  // level is the weight of the edge that caused it. The merge level of two superpixels is the
  // level of their lowest common ancestor.
  std::vector<int> tree_parent(static_cast<std::size_t>(n), -1);
  std::vector<float> tree_level(static_cast<std::size_t>(n), kNoBoundary);
  std::vector<int> tree_node_of_root(static_cast<std::size_t>(n));
  std::iota(tree_node_of_root.begin(), tree_node_of_root.end(), 0);
  UnionFind sets(n);
  for (const std::size_t k : edgesByWeight(ucg)) {
    const GraphEdge& e = ucg.edges[k];
    const int ra = sets.find(e.a);
    const int rb = sets.find(e.b);
    if (ra == rb) continue;
    const int node = static_cast<int>(tree_parent.size());
    tree_parent.push_back(-1);
    tree_level.push_back(e.weight);
    tree_parent[tree_node_of_root[ra]] = node;
    tree_parent[tree_node_of_root[rb]] = node;
    sets.unite(ra, rb);
    tree_node_of_root[sets.find(ra)] = node;
  }
  // Parents have larger ids than their children, so one backwards pass gives every depth.
  std::vector<int> depth(tree_parent.size(), 0);
  for (int i = static_cast<int>(tree_parent.size()) - 1; i >= 0; --i) {
    if (tree_parent[i] >= 0) depth[i] = depth[tree_parent[i]] + 1;
  }
  WeightedGraph levels = labelAdjacency(superpixel_labels, n);
  for (GraphEdge& e : levels.edges) {
    int a = e.a;
    int b = e.b;
    while (a != b && a >= 0 && b >= 0) {
      if (depth[a] >= depth[b]) {
        a = tree_parent[a];
      } else {
        b = tree_parent[b];
      }
    }
    e.weight = (a == b && a >= 0) ? tree_level[a] : std::numeric_limits<float>::infinity();
  }
  return levels;
}

cv::Mat ultrametricContourMap(const cv::Mat& superpixel_labels, const WeightedGraph& ucg,
                              const cv::Mat& mask) {
  checkMask(mask, superpixel_labels.size(), "ultrametricContourMap");
  const WeightedGraph levels = mergeLevels(superpixel_labels, ucg);
  // Lookup per node: its neighbours are a short sorted run of `levels.edges`.
  std::vector<std::size_t> first(static_cast<std::size_t>(ucg.node_count) + 1, 0);
  for (const GraphEdge& e : levels.edges) ++first[e.a + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  auto level = [&](int p, int q) {
    if (p == q) return kNoBoundary;
    if (p < 0 || q < 0) return std::numeric_limits<float>::infinity();
    if (p > q) std::swap(p, q);
    for (std::size_t k = first[p]; k < first[p + 1]; ++k) {
      if (levels.edges[k].b == q) return levels.edges[k].weight;
    }
    return std::numeric_limits<float>::infinity();  // not reached: every adjacent pair is listed
  };
  const cv::Mat& labels = superpixel_labels;
  auto inside = [&](int y, int x) { return mask.empty() || mask.at<std::uint8_t>(y, x) != 0; };
  auto normalised = [](int label) { return label < 0 ? -1 : label; };
  cv::Mat ucm(labels.size(), CV_32FC1, cv::Scalar(kNoBoundary));
  for (int y = 0; y < labels.rows; ++y) {
    for (int x = 0; x < labels.cols; ++x) {
      if (!inside(y, x)) continue;
      const int p = normalised(labels.at<int>(y, x));
      float value = kNoBoundary;
      constexpr int kDx[4] = {-1, 1, 0, 0};
      constexpr int kDy[4] = {0, 0, -1, 1};
      for (int k = 0; k < 4; ++k) {
        const int nx = x + kDx[k];
        const int ny = y + kDy[k];
        if (nx < 0 || ny < 0 || nx >= labels.cols || ny >= labels.rows || !inside(ny, nx)) {
          continue;
        }
        value = std::max(value, level(p, normalised(labels.at<int>(ny, nx))));
      }
      ucm.at<float>(y, x) = value;
    }
  }
  return ucm;
}

std::vector<float> spanningMergeLevels(const WeightedGraph& graph) {
  checkGraph(graph, "spanningMergeLevels");
  std::vector<float> levels;
  levels.reserve(static_cast<std::size_t>(std::max(0, graph.node_count - 1)));
  UnionFind sets(graph.node_count);
  for (const std::size_t k : edgesByWeight(graph)) {
    if (sets.unite(graph.edges[k].a, graph.edges[k].b)) levels.push_back(graph.edges[k].weight);
  }
  return levels;  // ascending: Kruskal takes the edges in weight order
}

}  // namespace dasp

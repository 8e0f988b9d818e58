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

double BoundaryCounts::precision() const {
  return partition_pixels == 0 ? 1.0 : static_cast<double>(precise_pixels) / partition_pixels;
}
double BoundaryCounts::recall() const {
  return reference_pixels == 0 ? 1.0 : static_cast<double>(recalled_pixels) / reference_pixels;
}
double BoundaryCounts::f1() const {
  const double p = precision();
  const double r = recall();
  return p + r > 0.0 ? 2.0 * p * r / (p + r) : 0.0;
}
BoundaryCounts& BoundaryCounts::operator+=(const BoundaryCounts& other) {
  partition_pixels += other.partition_pixels;
  precise_pixels += other.precise_pixels;
  reference_pixels += other.reference_pixels;
  recalled_pixels += other.recalled_pixels;
  return *this;
}

std::vector<BoundaryCounts> boundaryCurve(const cv::Mat& ucm, const cv::Mat& ground_truth,
                                          const cv::Mat& mask, const std::vector<float>& thresholds,
                                          int tolerance_px) {
  const char* what = "boundaryCurve";
  if (ucm.type() != CV_32FC1) throw std::invalid_argument("boundaryCurve: ucm must be CV_32FC1");
  checkMask(mask, ucm.size(), what);
  if (ground_truth.size() != ucm.size() || ground_truth.channels() != 1) {
    throw std::invalid_argument("boundaryCurve: ground truth must be one channel of the ucm size");
  }
  if (tolerance_px < 0) throw std::invalid_argument("boundaryCurve: tolerance_px must be >= 0");
  cv::Mat reference;
  ground_truth.convertTo(reference, CV_32S);
  const cv::Mat reference_boundary = metrics::boundaryMap(reference, mask);
  cv::Mat reference_near, ucm_near;  // fresh buffers: dilate must not write into its input
  if (tolerance_px == 0) {
    reference_near = reference_boundary;
    ucm_near = ucm;
  } else {
    // Same square window as metrics::boundaryScores; on the ucm the dilation is a max filter, so
    // ucm_near >= t exactly where a boundary pixel of the segmentation at t is within reach.
    const cv::Mat kernel = cv::getStructuringElement(
        cv::MORPH_RECT, cv::Size(2 * tolerance_px + 1, 2 * tolerance_px + 1));
    cv::dilate(reference_boundary, reference_near, kernel);
    cv::dilate(ucm, ucm_near, kernel);
  }
  // Sorted level values: partition pixels, precise ones, and the best level near each reference
  // boundary pixel; the counts at t are then the numbers of values >= t.
  std::vector<float> partition, precise, recalled;
  std::size_t reference_pixels = 0;
  for (int y = 0; y < ucm.rows; ++y) {
    const float* level = ucm.ptr<float>(y);
    const float* level_near = ucm_near.ptr<float>(y);
    const std::uint8_t* ref = reference_boundary.ptr<std::uint8_t>(y);
    const std::uint8_t* ref_near = reference_near.ptr<std::uint8_t>(y);
    for (int x = 0; x < ucm.cols; ++x) {
      if (level[x] >= 0.0f) {
        partition.push_back(level[x]);
        if (ref_near[x] != 0) precise.push_back(level[x]);
      }
      if (ref[x] != 0) {
        ++reference_pixels;
        if (level_near[x] >= 0.0f) recalled.push_back(level_near[x]);
      }
    }
  }
  std::sort(partition.begin(), partition.end());
  std::sort(precise.begin(), precise.end());
  std::sort(recalled.begin(), recalled.end());
  auto at_least = [](const std::vector<float>& values, float t) {
    return static_cast<std::size_t>(values.end() -
                                    std::lower_bound(values.begin(), values.end(), t));
  };
  std::vector<BoundaryCounts> curve(thresholds.size());
  for (std::size_t i = 0; i < thresholds.size(); ++i) {
    // Levels are >= 0, so every t <= 0 gives the full superpixel boundary.
    const float t = std::max(thresholds[i], 0.0f);
    BoundaryCounts& c = curve[i];
    c.threshold = thresholds[i];
    c.partition_pixels = at_least(partition, t);
    c.precise_pixels = at_least(precise, t);
    c.reference_pixels = reference_pixels;
    c.recalled_pixels = at_least(recalled, t);
  }
  return curve;
}

WeightedGraph ultrametricContourGraph(const Superpixels& superpixels, const SdaspConfig& config) {
  WeightedGraph ucg = buildSuperpixelGraph(superpixels, config.graph);
  const std::vector<float> global = globalizeEdgeWeights(ucg, config.spectral);
  for (std::size_t k = 0; k < ucg.edges.size(); ++k) ucg.edges[k].weight = global[k];
  return ucg;
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

}  // namespace dasp

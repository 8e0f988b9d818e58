#include "dasp/superpixel_graph.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace dasp {
namespace {

void checkConfig(const SuperpixelGraphConfig& config, const char* what) {
  if (config.min_border_pairs < 0 || !(config.weight_color >= 0.0f) ||
      !(config.weight_position >= 0.0f) || !(config.weight_normal >= 0.0f) ||
      !(config.radius_m >= 0.0f)) {
    throw std::invalid_argument(std::string(what) + ": Theta, weights and radius must be >= 0");
  }
}

float distance(const Superpixel& a, const Superpixel& b, const SuperpixelGraphConfig& config) {
  float d = config.weight_color * (a.color - b.color).norm();  // eq. 4.19
  const float radius = config.radius_m > 0.0f ? config.radius_m : 0.5f * (a.radius_m + b.radius_m);
  if (radius > 0.0f) {
    const Eigen::Vector3f delta = a.position - b.position;
    const float length = delta.norm();
    d += config.weight_position * std::max(0.0f, length - 2.0f * radius) / (2.0f * radius);
    if (length > 0.0f) {
      // eq. 4.21, concave edges only. Our normals point towards the camera (out of the surface);
      // with them (n_a - n_b) . (v_a - v_b) > 0 on a convex edge (a sphere: n = (v - c) / r), so
      // the sign is turned to keep the thesis' intent: cost for concave, none for convex.
      d += config.weight_normal * std::max(0.0f, (b.normal - a.normal).dot(delta) / length);
    }
  }
  return d;
}

}  // namespace

float superpixelSimilarity(const Superpixel& a, const Superpixel& b,
                           const SuperpixelGraphConfig& config) {
  checkConfig(config, "superpixelSimilarity");
  return distance(a, b, config);
}

WeightedGraph labelAdjacency(const cv::Mat& labels, int label_count) {
  if (labels.type() != CV_32SC1) {
    throw std::invalid_argument("labelAdjacency: labels must be CV_32SC1");
  }
  if (label_count < 0) throw std::invalid_argument("labelAdjacency: negative label_count");
  std::unordered_map<std::uint64_t, int> pairs;
  auto add = [&](int p, int q) {
    if (p < 0 || q < 0 || p == q) return;
    if (p >= label_count || q >= label_count) {
      throw std::invalid_argument("labelAdjacency: label " + std::to_string(std::max(p, q)) +
                                  " >= label count " + std::to_string(label_count));
    }
    if (p > q) std::swap(p, q);
    ++pairs[(static_cast<std::uint64_t>(p) << 32) | static_cast<std::uint32_t>(q)];
  };
  for (int y = 0; y < labels.rows; ++y) {
    const int* row = labels.ptr<int>(y);
    const int* below = y + 1 < labels.rows ? labels.ptr<int>(y + 1) : nullptr;
    for (int x = 0; x < labels.cols; ++x) {
      if (x + 1 < labels.cols && row[x] != row[x + 1]) add(row[x], row[x + 1]);
      if (below != nullptr && row[x] != below[x]) add(row[x], below[x]);
    }
  }
  WeightedGraph graph;
  graph.node_count = label_count;
  graph.edges.reserve(pairs.size());
  for (const auto& [key, count] : pairs) {
    graph.edges.push_back({static_cast<int>(key >> 32), static_cast<int>(key & 0xffffffffu),
                           static_cast<float>(count)});
  }
  std::sort(graph.edges.begin(), graph.edges.end(), [](const GraphEdge& l, const GraphEdge& r) {
    return l.a != r.a ? l.a < r.a : l.b < r.b;
  });
  return graph;
}

WeightedGraph buildSuperpixelGraph(const Superpixels& superpixels,
                                   const SuperpixelGraphConfig& config) {
  checkConfig(config, "buildSuperpixelGraph");
  const int n = static_cast<int>(superpixels.superpixels.size());
  const WeightedGraph adjacency = labelAdjacency(superpixels.labels, n);
  WeightedGraph graph;
  graph.node_count = n;
  graph.edges.reserve(adjacency.edges.size());
  for (const GraphEdge& e : adjacency.edges) {
    if (e.weight <= static_cast<float>(config.min_border_pairs)) continue;  // eq. 4.16
    const float d = distance(superpixels.superpixels[e.a], superpixels.superpixels[e.b], config);
    graph.edges.push_back({e.a, e.b, std::exp(-d)});  // eq. 4.18
  }
  return graph;
}

}  // namespace dasp

// Semi-Supervised Hysteresis Segmentation (thesis §5.4.5).
#include "dasp/hysteresis_segmentation.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

namespace dasp {
namespace {

int findRoot(std::vector<int>& parent, int i) {
  while (parent[static_cast<std::size_t>(i)] != i) {
    parent[static_cast<std::size_t>(i)] =
        parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    i = parent[static_cast<std::size_t>(i)];
  }
  return i;
}

}  // namespace

HysteresisResult hysteresisSegmentation(const WeightedGraph& boundary_graph,
                                        const std::vector<std::int64_t>& supervised,
                                        const std::vector<double>& node_size,
                                        const HysteresisConfig& config, std::int64_t& next_label) {
  const int n = boundary_graph.node_count;
  if (n < 0 || supervised.size() != static_cast<std::size_t>(n)) {
    throw std::invalid_argument("hysteresisSegmentation: one supervised label per node needed");
  }
  if (!node_size.empty() && node_size.size() != static_cast<std::size_t>(n)) {
    throw std::invalid_argument("hysteresisSegmentation: node_size must be empty or per node");
  }
  if (!(config.force <= config.normal && config.normal <= config.grant)) {
    throw std::invalid_argument("hysteresisSegmentation: need force <= normal <= grant");
  }
  // 1.-2. Edges in ascending weight; each merge rule by the confidence of the two labels.
  std::vector<int> order(boundary_graph.edges.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) {
    return boundary_graph.edges[static_cast<std::size_t>(x)].weight <
           boundary_graph.edges[static_cast<std::size_t>(y)].weight;
  });
  // The rules look at the labels of the current segments (eq. 5.19 uses the labelling Gamma_i
  // that the merges so far produced), not of the single strands: a segment is supervised if it
  // holds a supervised strand, so a new strand that joined segment A cannot then bridge A to a
  // different supervised segment B by a normal merge.
  std::vector<int> parent(static_cast<std::size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<std::int64_t> segment_label(supervised);  // per root
  std::vector<double> supervised_size(static_cast<std::size_t>(n), 0.0);
  for (int i = 0; i < n; ++i) {
    if (supervised[static_cast<std::size_t>(i)] >= 0) {
      supervised_size[static_cast<std::size_t>(i)] =
          node_size.empty() ? 1.0 : node_size[static_cast<std::size_t>(i)];
    }
  }
  for (const int index : order) {
    const GraphEdge& e = boundary_graph.edges[static_cast<std::size_t>(index)];
    if (e.a < 0 || e.b < 0 || e.a >= n || e.b >= n) {
      throw std::invalid_argument("hysteresisSegmentation: edge out of range");
    }
    if (!(e.weight < config.grant)) break;  // no rule can merge any later edge
    const int ra = findRoot(parent, e.a), rb = findRoot(parent, e.b);
    if (ra == rb) continue;
    const std::int64_t la = segment_label[static_cast<std::size_t>(ra)];
    const std::int64_t lb = segment_label[static_cast<std::size_t>(rb)];
    bool merge = e.weight < config.force;                                // forced merge
    if (!merge && (la < 0 || lb < 0)) merge = e.weight < config.normal;  // normal merge
    if (!merge && la >= 0 && la == lb) merge = e.weight < config.grant;  // granted merge
    if (!merge) continue;
    const int root = std::min(ra, rb), child = std::max(ra, rb);
    parent[static_cast<std::size_t>(child)] = root;
    // The merged segment carries the label of its heavier supervised part.
    const double sa = supervised_size[static_cast<std::size_t>(ra)];
    const double sb = supervised_size[static_cast<std::size_t>(rb)];
    segment_label[static_cast<std::size_t>(root)] = lb < 0 || (la >= 0 && sa >= sb) ? la : lb;
    supervised_size[static_cast<std::size_t>(root)] = sa + sb;
  }
  // 3. Connected components with their size and label histogram.
  std::vector<int> component(static_cast<std::size_t>(n), -1);
  std::vector<int> root_component(static_cast<std::size_t>(n), -1);
  int count = 0;
  for (int i = 0; i < n; ++i) {
    const int r = findRoot(parent, i);
    int& c = root_component[static_cast<std::size_t>(r)];
    if (c < 0) c = count++;
    component[static_cast<std::size_t>(i)] = c;
  }
  std::vector<double> size(static_cast<std::size_t>(count), 0.0);
  std::vector<std::unordered_map<std::int64_t, double>> histogram(static_cast<std::size_t>(count));
  for (int i = 0; i < n; ++i) {
    const double s = node_size.empty() ? 1.0 : node_size[static_cast<std::size_t>(i)];
    const int c = component[static_cast<std::size_t>(i)];
    size[static_cast<std::size_t>(c)] += s;
    const std::int64_t l = supervised[static_cast<std::size_t>(i)];
    if (l >= 0) histogram[static_cast<std::size_t>(c)][l] += s;
  }
  // 4. Largest component first: its most frequent previous label if still free, else a new one.
  std::vector<int> by_size(static_cast<std::size_t>(count));
  std::iota(by_size.begin(), by_size.end(), 0);
  std::stable_sort(by_size.begin(), by_size.end(), [&](int x, int y) {
    return size[static_cast<std::size_t>(x)] > size[static_cast<std::size_t>(y)];
  });
  HysteresisResult result;
  result.component_count = count;
  std::vector<std::int64_t> component_label(static_cast<std::size_t>(count), -1);
  std::unordered_set<std::int64_t> taken;
  for (const int c : by_size) {
    std::int64_t best = -1;
    double best_count = 0.0;
    for (const auto& [label, weight] : histogram[static_cast<std::size_t>(c)]) {
      if (weight > best_count || (weight == best_count && label < best)) {
        best = label;
        best_count = weight;
      }
    }
    if (best >= 0 && taken.insert(best).second) {
      component_label[static_cast<std::size_t>(c)] = best;
      ++result.labels_continued;
    } else {
      component_label[static_cast<std::size_t>(c)] = next_label++;
      ++result.labels_created;
    }
  }
  result.labels.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    result.labels[static_cast<std::size_t>(i)] =
        component_label[static_cast<std::size_t>(component[static_cast<std::size_t>(i)])];
  }
  return result;
}

}  // namespace dasp

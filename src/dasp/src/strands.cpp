// Superpixel strands and the reduced strand graph of t-DASP (thesis §5.3, §5.4.1).
#include "dasp/strands.h"

#include <algorithm>
#include <stdexcept>

namespace dasp {

bool plausibleContinuation(const Superpixel& previous, const Superpixel& current,
                           const StrandConfig& config) {
  if ((current.color - previous.color).norm() >= config.max_color_change) return false;
  if (1.0f - current.normal.dot(previous.normal) >= config.max_normal_change) return false;
  const float radius = 0.5f * (current.radius_m + previous.radius_m);
  const float moved = (current.position - previous.position).norm();
  return moved < config.max_position_change * radius;
}

StrandGraph::StrandGraph(const StrandConfig& config) : config_(config) {
  if (config.max_strands < 1) throw std::invalid_argument("StrandGraph: max_strands must be >= 1");
  if (!(config.max_color_change > 0.0f) || !(config.max_normal_change > 0.0f) ||
      !(config.max_position_change > 0.0f)) {
    throw std::invalid_argument("StrandGraph: plausibility thresholds must be positive");
  }
}

std::vector<int> StrandGraph::addFrame(const StreamingDaspFrame& frame,
                                       const WeightedGraph& superpixel_graph) {
  const auto& superpixels = frame.superpixels.superpixels;
  const std::size_t n = superpixels.size();
  if (frame.predecessor.size() != n) {
    throw std::invalid_argument("StrandGraph: predecessor list does not match the superpixels");
  }
  if (superpixel_graph.node_count != static_cast<int>(n)) {
    throw std::invalid_argument("StrandGraph: superpixel graph does not match the superpixels");
  }
  const std::int64_t t = current_frame_ + 1;
  current_frame_ = t;
  continued_ = started_ = 0;

  // 1. Continue strands along the DDS relation (eq. 5.9) where eq. 5.10 holds, else start one.
  std::vector<std::int64_t> strand_of(n, -1);
  for (std::size_t j = 0; j < n; ++j) {
    const int p = frame.predecessor[j];
    if (p >= 0 && static_cast<std::size_t>(p) < previous_frame_strand_.size()) {
      const auto it = index_of_.find(previous_frame_strand_[static_cast<std::size_t>(p)]);
      if (it != index_of_.end()) {
        Strand& s = strands_[static_cast<std::size_t>(it->second)];
        // end_frame == t - 1: not continued yet in this frame (the relation is one-to-one).
        if (s.end_frame == t - 1 && plausibleContinuation(s.last, superpixels[j], config_)) {
          s.end_frame = t;
          s.last = superpixels[j];
          strand_of[j] = s.id;
          ++continued_;
          continue;
        }
      }
    }
    Strand s;
    s.id = next_strand_id_++;
    s.start_frame = t;
    s.end_frame = t;
    s.last = superpixels[j];
    index_of_[s.id] = static_cast<int>(strands_.size());
    strands_.push_back(s);
    neighbours_.emplace_back();
    strand_of[j] = s.id;
    ++started_;
  }

  // 2. Accumulate the superpixel edge weights on the strand edges (numerator of eq. 5.12).
  for (const GraphEdge& e : superpixel_graph.edges) {
    if (e.a < 0 || e.b < 0 || e.a >= static_cast<int>(n) || e.b >= static_cast<int>(n) ||
        e.a == e.b) {
      throw std::invalid_argument("StrandGraph: superpixel graph edge out of range");
    }
    const std::int64_t sa = strand_of[static_cast<std::size_t>(e.a)];
    const std::int64_t sb = strand_of[static_cast<std::size_t>(e.b)];
    auto [it, inserted] = edges_.try_emplace(key(sa, sb));
    it->second.weight_sum += e.weight;
    if (inserted) {
      neighbours_[static_cast<std::size_t>(index_of_[sa])].push_back(sb);
      neighbours_[static_cast<std::size_t>(index_of_[sb])].push_back(sa);
    }
  }
  previous_frame_strand_ = strand_of;

  // 3. Reduction (§5.4.1).
  reduce();
  std::vector<int> result(n);
  for (std::size_t j = 0; j < n; ++j) result[j] = index_of_.at(strand_of[j]);
  return result;
}

void StrandGraph::reduce() {
  pruned_ = 0;
  const int excess = static_cast<int>(strands_.size()) - config_.max_strands;
  if (excess <= 0) return;
  // Oldest end time first (ties: older start, then lower id); active strands never go.
  std::vector<int> order(strands_.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const Strand& sa = strands_[static_cast<std::size_t>(a)];
    const Strand& sb = strands_[static_cast<std::size_t>(b)];
    if (sa.end_frame != sb.end_frame) return sa.end_frame < sb.end_frame;
    return sa.id < sb.id;
  });
  std::vector<std::uint8_t> drop(strands_.size(), 0);
  for (int k = 0; k < excess; ++k) {
    const int i = order[static_cast<std::size_t>(k)];
    if (strands_[static_cast<std::size_t>(i)].end_frame == current_frame_) break;
    drop[static_cast<std::size_t>(i)] = 1;
    ++pruned_;
  }
  if (pruned_ == 0) return;
  // Remove the dropped strands' edges (from both ends).
  for (std::size_t i = 0; i < strands_.size(); ++i) {
    if (!drop[i]) continue;
    const std::int64_t id = strands_[i].id;
    for (const std::int64_t other : neighbours_[i]) {
      edges_.erase(key(id, other));
      const int oi = index_of_.at(other);
      if (drop[static_cast<std::size_t>(oi)]) continue;
      auto& list = neighbours_[static_cast<std::size_t>(oi)];
      list.erase(std::remove(list.begin(), list.end(), id), list.end());
    }
  }
  // Compact the strand arrays and the id index.
  std::size_t kept = 0;
  for (std::size_t i = 0; i < strands_.size(); ++i) {
    if (drop[i]) {
      index_of_.erase(strands_[i].id);
      continue;
    }
    if (kept != i) {
      strands_[kept] = strands_[i];
      neighbours_[kept] = std::move(neighbours_[i]);
    }
    index_of_[strands_[kept].id] = static_cast<int>(kept);
    ++kept;
  }
  strands_.resize(kept);
  neighbours_.resize(kept);
}

WeightedGraph StrandGraph::graph() const {
  WeightedGraph g;
  g.node_count = static_cast<int>(strands_.size());
  g.edges.reserve(edges_.size());
  for (const auto& [k, sum] : edges_) {
    const int ia = index_of_.at(k.a), ib = index_of_.at(k.b);
    const Strand& p = strands_[static_cast<std::size_t>(ia)];
    const Strand& q = strands_[static_cast<std::size_t>(ib)];
    // |t_pq|: frames in which both strands have a superpixel (eq. 5.12).
    const std::int64_t overlap =
        std::min(p.end_frame, q.end_frame) - std::max(p.start_frame, q.start_frame) + 1;
    const double w = sum.weight_sum / static_cast<double>(std::max<std::int64_t>(1, overlap));
    g.edges.push_back({std::min(ia, ib), std::max(ia, ib), static_cast<float>(w)});
  }
  std::sort(g.edges.begin(), g.edges.end(), [](const GraphEdge& x, const GraphEdge& y) {
    return x.a != y.a ? x.a < y.a : x.b < y.b;
  });
  return g;
}

}  // namespace dasp

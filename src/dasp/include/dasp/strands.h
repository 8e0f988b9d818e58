// Superpixel strands and the strand graph of t-DASP (thesis §5.3, §5.4.1): temporal chains of
// superpixels that represent the same piece of surface, linked by the seed origins of streaming
// DASP and pruned by a plausibility test (eq. 5.10); strands are the nodes of a graph whose edge
// weights average the per-frame superpixel graph weights over the strands' common lifetime
// (eq. 5.12). The graph keeps at most a fixed number of strands (the most recently active ones),
// so that memory and time per frame stay bounded on an endless stream.
#pragma once

#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

#include "dasp/dasp.h"
#include "dasp/streaming_dasp.h"
#include "dasp/superpixel_graph.h"

namespace dasp {

/// Parameters of the strands and the strand graph. The thesis gives no values for the
/// thresholds of eq. 5.10; these are loose bounds on what one superpixel can change between two
/// frames at 30 Hz while still showing the same surface.
struct StrandConfig {
  /// theta_c: largest RGB distance (colours in [0, 1]) of a continued superpixel.
  float max_color_change = 0.2f;
  /// theta_n: largest 1 - n_prev . n_cur of the plane-fit normals (0.3: about 45 deg).
  float max_normal_change = 0.3f;
  /// theta_v: largest 3D distance of the mean points, in multiples of the superpixel radius R
  /// (the camera moves, so this bounds camera motion plus DALIC drift per frame).
  float max_position_change = 2.0f;
  /// Strands kept in the graph (oldest end time deleted first, §5.4.1). Must exceed the number
  /// of superpixels per frame; strands of the current frame are never deleted.
  int max_strands = 3000;
  /// Superpixel graph and d_S of every frame (eq. 4.16-4.21, s-DASP's defaults).
  SuperpixelGraphConfig graph;
};

/// The plausibility test of eq. 5.10: true if `current` may continue the strand of `previous`
/// (colour, normal and position change all below their thresholds).
bool plausibleContinuation(const Superpixel& previous, const Superpixel& current,
                           const StrandConfig& config);

/// One superpixel strand T_k.
struct Strand {
  std::int64_t id = -1;          ///< unique in the stream, never reused
  std::int64_t start_frame = 0;  ///< t_k
  std::int64_t end_frame = 0;    ///< t_k + l_k - 1 (active if equal to the current frame)
  Superpixel last;               ///< its superpixel in frame end_frame
  /// Segment label assigned at the end of the last frame it was in the graph (-1: none yet).
  std::int64_t segment_label = -1;
  std::int64_t length() const { return end_frame - start_frame + 1; }
};

/// The reduced superpixel strand graph G_T* of a stream.
class StrandGraph {
 public:
  explicit StrandGraph(const StrandConfig& config = {});

  /// Adds one frame of streaming DASP. superpixel_graph: its superpixel neighbour graph
  /// (buildSuperpixelGraph with config.graph). Continues or starts strands, accumulates the
  /// edge weights of eq. 5.12 and reduces the graph to config.max_strands. Returns per
  /// superpixel the index of its strand in strands(). Frames must come in increasing order.
  std::vector<int> addFrame(const StreamingDaspFrame& frame, const WeightedGraph& superpixel_graph);

  /// Stored strands (node i of graph() is strands()[i]); valid until the next addFrame.
  const std::vector<Strand>& strands() const { return strands_; }
  /// Strand graph with the averaged weights W_T (eq. 5.12), edges sorted by (a, b).
  WeightedGraph graph() const;
  /// Sets the segment label of stored strand i (by index in strands()).
  void setSegmentLabel(int i, std::int64_t label) {
    strands_[static_cast<std::size_t>(i)].segment_label = label;
  }
  std::size_t edgeCount() const { return edges_.size(); }
  std::int64_t currentFrame() const { return current_frame_; }
  /// Number of strands continued / started / deleted by the reduction in the last addFrame.
  int continuedLastFrame() const { return continued_; }
  int startedLastFrame() const { return started_; }
  int prunedLastFrame() const { return pruned_; }

 private:
  struct EdgeSum {
    double weight_sum = 0.0;  ///< sum over frames of the superpixel edge weight
  };
  struct EdgeKey {
    std::int64_t a = 0, b = 0;  ///< strand ids, a < b
    bool operator==(const EdgeKey& o) const { return a == o.a && b == o.b; }
  };
  struct EdgeKeyHash {
    std::size_t operator()(const EdgeKey& k) const {
      return std::hash<std::uint64_t>()(static_cast<std::uint64_t>(k.a) * 0x9E3779B97F4A7C15ULL ^
                                        static_cast<std::uint64_t>(k.b));
    }
  };
  static EdgeKey key(std::int64_t a, std::int64_t b) {
    return a < b ? EdgeKey{a, b} : EdgeKey{b, a};
  }
  void reduce();

  StrandConfig config_;
  std::int64_t current_frame_ = -1;
  std::int64_t next_strand_id_ = 0;
  std::vector<Strand> strands_;
  std::unordered_map<std::int64_t, int> index_of_;     ///< strand id -> index in strands_
  std::vector<std::vector<std::int64_t>> neighbours_;  ///< per strand index: neighbour ids
  std::unordered_map<EdgeKey, EdgeSum, EdgeKeyHash> edges_;
  std::vector<std::int64_t> previous_frame_strand_;  ///< per superpixel of the last frame
  int continued_ = 0, started_ = 0, pruned_ = 0;
};

}  // namespace dasp

// s-DASP: superpixel graph, spectral globalisation, ultrametric contour graph/map, segmentation.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "dasp/dasp.h"
#include "dasp/metrics.h"
#include "dasp/sdasp.h"
#include "dasp/segmentation.h"
#include "dasp/spectral.h"
#include "dasp/superpixel_graph.h"
#include "dasp_synthetic.h"

namespace dasp {
namespace {

// Two cliques of `size` nodes with unit weights, joined by one edge of weight `bridge`.
WeightedGraph twoCliques(int size, float bridge) {
  WeightedGraph graph;
  graph.node_count = 2 * size;
  for (int offset : {0, size}) {
    for (int i = 0; i < size; ++i) {
      for (int j = i + 1; j < size; ++j) graph.edges.push_back({offset + i, offset + j, 1.0f});
    }
  }
  graph.edges.push_back({size - 1, size, bridge});
  return graph;
}

// A w x h grid graph with random weights in [0.2, 1] (distinct eigenvalues, like a superpixel
// graph).
WeightedGraph randomGrid(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> weight(0.2f, 1.0f);
  WeightedGraph graph;
  graph.node_count = w * h;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int i = y * w + x;
      if (x + 1 < w) graph.edges.push_back({i, i + 1, weight(rng)});
      if (y + 1 < h) graph.edges.push_back({i, i + w, weight(rng)});
    }
  }
  return graph;
}

int countDistinct(const std::vector<int>& labels) {
  return static_cast<int>(std::set<int>(labels.begin(), labels.end()).size());
}

TEST(SuperpixelGraph, DistanceTermsFollowTheThesis) {
  SuperpixelGraphConfig config;
  config.weight_color = 1.0f;
  config.weight_position = 1.0f;
  config.weight_normal = 1.0f;
  Superpixel a, b;
  a.radius_m = b.radius_m = 0.02f;
  a.position = {0.0f, 0.0f, 1.0f};
  b.position = {0.03f, 0.0f, 1.0f};  // closer than 2R: tolerated
  EXPECT_FLOAT_EQ(superpixelSimilarity(a, b, config), 0.0f);
  b.position = {0.08f, 0.0f, 1.0f};  // 2R + 0.04 -> (0.04) / 0.04 = 1
  EXPECT_NEAR(superpixelSimilarity(a, b, config), 1.0f, 1e-5f);
  b.position = {0.03f, 0.0f, 1.0f};
  b.color = {0.3f, 0.4f, 0.0f};
  EXPECT_NEAR(superpixelSimilarity(a, b, config), 0.5f, 1e-5f);
  b.color = a.color;
  // Convex edge (a roof, normals towards the camera point away from each other): no cost.
  a.normal = Eigen::Vector3f(-0.6f, 0.0f, -0.8f);
  b.normal = Eigen::Vector3f(0.6f, 0.0f, -0.8f);
  EXPECT_FLOAT_EQ(superpixelSimilarity(a, b, config), 0.0f);
  // Concave edge (a valley): (n_a - n_b) . (v_a - v_b) / |v_a - v_b| = 1.2.
  std::swap(a.normal, b.normal);
  EXPECT_NEAR(superpixelSimilarity(a, b, config), 1.2f, 1e-5f);
  config.weight_color = -1.0f;
  EXPECT_THROW(superpixelSimilarity(a, b, config), std::invalid_argument);
}

TEST(SuperpixelGraph, EdgesNeedMoreThanThetaBorderPairs) {
  Superpixels sp;
  sp.labels = cv::Mat(4, 6, CV_32SC1, cv::Scalar(0));
  sp.labels.colRange(3, 6).setTo(1);  // 0|1 share 4 pairs
  sp.labels.at<int>(3, 0) = 2;        // 2 touches 0 (2 pairs)
  sp.labels.at<int>(0, 5) = -1;       // unlabelled pixels are no neighbours
  sp.superpixels.resize(3);
  for (int i = 0; i < 3; ++i) sp.superpixels[i].id = i;
  SuperpixelGraphConfig config;
  config.min_border_pairs = 2;
  WeightedGraph graph = buildSuperpixelGraph(sp, config);
  ASSERT_EQ(graph.node_count, 3);
  ASSERT_EQ(graph.edges.size(), 1u);
  EXPECT_EQ(graph.edges[0].a, 0);
  EXPECT_EQ(graph.edges[0].b, 1);
  EXPECT_FLOAT_EQ(graph.edges[0].weight, 1.0f);  // identical features: exp(0)
  config.min_border_pairs = 1;
  EXPECT_EQ(buildSuperpixelGraph(sp, config).edges.size(), 2u);
  sp.superpixels.resize(2);  // label 2 without a superpixel
  EXPECT_THROW(buildSuperpixelGraph(sp, config), std::invalid_argument);
}

TEST(Spectral, TwoCliquesSplitAtTheWeakEdge) {
  const WeightedGraph graph = twoCliques(8, 0.05f);
  const std::vector<float> global = globalizeEdgeWeights(graph);
  ASSERT_EQ(global.size(), graph.edges.size());
  const float bridge = global.back();
  for (std::size_t k = 0; k + 1 < global.size(); ++k) EXPECT_LT(global[k], 0.5f * bridge);
  WeightedGraph ucg = graph;
  for (std::size_t k = 0; k < global.size(); ++k) ucg.edges[k].weight = global[k];
  const std::vector<int> segments = segmentGraph(ucg, 0.5f * bridge);
  EXPECT_EQ(countDistinct(segments), 2);
  for (int i = 0; i < 8; ++i) {
    EXPECT_EQ(segments[i], segments[0]);
    EXPECT_EQ(segments[8 + i], segments[8]);
  }
  EXPECT_NE(segments[0], segments[8]);
}

TEST(Spectral, SparseEigenpairsMatchDenseReference) {
  const WeightedGraph graph = randomGrid(15, 12, 3);
  SpectralConfig config;
  config.dense_max_nodes = 0;  // force Spectra
  const Eigenpairs sparse = smallestEigenpairs(graph, 9, config);
  const Eigenpairs dense = smallestEigenpairsDense(graph, 9);
  ASSERT_EQ(sparse.values.size(), 9);
  ASSERT_EQ(dense.values.size(), 9);
  EXPECT_NEAR(dense.values[0], 0.0, 1e-9);
  for (int t = 0; t < 9; ++t) {
    EXPECT_NEAR(sparse.values[t], dense.values[t], 1e-7) << t;
    // Same vector up to sign (the sign is fixed by the same rule, so exactly the same).
    EXPECT_LT((sparse.vectors.col(t) - dense.vectors.col(t)).cwiseAbs().maxCoeff(), 1e-5) << t;
  }
  // Generalised problem: L x = lambda D x with x^T D x = 1.
  Eigen::VectorXd degree = Eigen::VectorXd::Zero(graph.node_count);
  for (const GraphEdge& e : graph.edges) {
    degree[e.a] += e.weight;
    degree[e.b] += e.weight;
  }
  const Eigen::VectorXd x = sparse.vectors.col(4);
  Eigen::VectorXd lx = degree.cwiseProduct(x);
  for (const GraphEdge& e : graph.edges) {
    lx[e.a] -= e.weight * x[e.b];
    lx[e.b] -= e.weight * x[e.a];
  }
  EXPECT_LT((lx - sparse.values[4] * degree.cwiseProduct(x)).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_NEAR(x.dot(degree.cwiseProduct(x)), 1.0, 1e-9);
  // The globalised weights agree too and are deterministic.
  SpectralConfig dense_config;
  dense_config.dense_max_nodes = 1000;
  config.eigenvector_count = dense_config.eigenvector_count = 8;
  const std::vector<float> from_sparse = globalizeEdgeWeights(graph, config);
  const std::vector<float> from_dense = globalizeEdgeWeights(graph, dense_config);
  for (std::size_t k = 0; k < from_sparse.size(); ++k) {
    EXPECT_NEAR(from_sparse[k], from_dense[k], 1e-4f);
  }
  EXPECT_EQ(from_sparse, globalizeEdgeWeights(graph, config));
}

TEST(Spectral, DisconnectedTinyAndOversizedRequests) {
  SpectralConfig config;
  config.eigenvector_count = 100;  // k >= n everywhere below
  EXPECT_TRUE(globalizeEdgeWeights(WeightedGraph{}, config).empty());
  EXPECT_TRUE(globalizeEdgeWeights(WeightedGraph{1, {}}, config).empty());
  const std::vector<float> pair = globalizeEdgeWeights(WeightedGraph{2, {{0, 1, 0.5f}}}, config);
  ASSERT_EQ(pair.size(), 1u);
  EXPECT_TRUE(std::isfinite(pair[0]));
  // Two cliques with a zero-weight bridge, an isolated node and a separate pair.
  WeightedGraph graph = twoCliques(5, 0.0f);
  graph.node_count += 3;
  graph.edges.push_back({11, 12, 1.0f});
  const std::vector<float> global = globalizeEdgeWeights(graph, config);
  ASSERT_EQ(global.size(), graph.edges.size());
  for (float w : global) {
    EXPECT_TRUE(std::isfinite(w));
    EXPECT_GE(w, 0.0f);
    EXPECT_LE(w, 1.0f);
  }
  EXPECT_FLOAT_EQ(global[graph.edges.size() - 2], 1.0f);  // the unconnected bridge
  WeightedGraph ucg = graph;
  for (std::size_t k = 0; k < global.size(); ++k) ucg.edges[k].weight = global[k];
  EXPECT_EQ(countDistinct(segmentGraph(ucg, 0.999f)), 4);  // two cliques, isolated node, pair
  EXPECT_EQ(countDistinct(segmentGraph(ucg, 1.0f)), 4);    // weight 1 < 1 is false
  EXPECT_EQ(countDistinct(segmentGraph(ucg, 1.5f)), 3);    // the zero bridge joins last
  EXPECT_THROW(globalizeEdgeWeights(WeightedGraph{2, {{0, 2, 1.0f}}}), std::invalid_argument);
  EXPECT_THROW(globalizeEdgeWeights(WeightedGraph{2, {{0, 1, -1.0f}}}), std::invalid_argument);
  config.eigenvector_count = 0;
  EXPECT_THROW(globalizeEdgeWeights(graph, config), std::invalid_argument);
}

TEST(Segmentation, SweepEqualsPerThresholdLabelling) {
  WeightedGraph ucg = randomGrid(20, 15, 7);
  ucg.edges.resize(ucg.edges.size() - 40);  // some nodes end up less connected
  const std::vector<float> thresholds = {0.9f, 0.0f, 0.5f, 0.21f, 0.75f, 1.1f, 0.5f, 0.33f};
  const std::vector<std::vector<int>> sweep = segmentGraphSweep(ucg, thresholds);
  ASSERT_EQ(sweep.size(), thresholds.size());
  for (std::size_t i = 0; i < thresholds.size(); ++i) {
    EXPECT_EQ(sweep[i], segmentGraph(ucg, thresholds[i])) << thresholds[i];
  }
  EXPECT_EQ(countDistinct(sweep[1]), ucg.node_count);  // t = 0 merges nothing
  // Larger thresholds merge more; above every weight only the connected components are left.
  EXPECT_GT(countDistinct(sweep[3]), countDistinct(sweep[2]));
  EXPECT_GT(countDistinct(sweep[2]), countDistinct(sweep[4]));
  EXPECT_GE(countDistinct(sweep[4]), countDistinct(sweep[5]));
  WeightedGraph connected = ucg;
  for (GraphEdge& e : connected.edges) e.weight = 0.0f;
  EXPECT_EQ(sweep[5], segmentGraph(connected, 0.5f));
}

// A label image of superpixels on a grid, their UCG with random weights, and a ground truth.
struct GridScene {
  cv::Mat labels;
  WeightedGraph ucg;
  cv::Mat truth;
  cv::Mat mask;
};

GridScene gridScene() {
  GridScene s;
  const int cells_x = 8, cells_y = 6, cell = 9;
  s.labels = cv::Mat(cells_y * cell, cells_x * cell, CV_32SC1);
  for (int y = 0; y < s.labels.rows; ++y) {
    for (int x = 0; x < s.labels.cols; ++x) {
      // Slightly irregular borders so that superpixel edges are not straight.
      const int cx = std::min(cells_x - 1, (x + (y % 3 == 0 ? 1 : 0)) / cell);
      s.labels.at<int>(y, x) = (y / cell) * cells_x + cx;
    }
  }
  s.labels(cv::Rect(20, 20, 4, 4)).setTo(-1);  // unlabelled pixels
  s.ucg = randomGrid(cells_x, cells_y, 11);
  s.ucg.edges.erase(s.ucg.edges.begin() + 5);  // an adjacent pair without edge
  s.truth = cv::Mat(s.labels.size(), CV_16UC1, cv::Scalar(1));
  s.truth(cv::Rect(0, 0, 30, 40)).setTo(2);
  s.truth(cv::Rect(50, 10, 20, 30)).setTo(3);
  s.mask = cv::Mat(s.labels.size(), CV_8UC1, cv::Scalar(255));
  s.mask(cv::Rect(60, 40, 12, 14)).setTo(0);
  return s;
}

TEST(Segmentation, UltrametricMapThresholdsToTheSegmentationBoundary) {
  const GridScene s = gridScene();
  const cv::Mat ucm = ultrametricContourMap(s.labels, s.ucg, s.mask);
  for (float t : {0.0f, 0.3f, 0.45f, 0.6f, 0.8f, 0.95f, 1.5f}) {
    const cv::Mat segments = segmentPixels(s.labels, segmentGraph(s.ucg, t));
    const cv::Mat expected = metrics::boundaryMap(segments, s.mask);
    cv::Mat thresholded = ucm >= t;
    EXPECT_EQ(cv::countNonZero(thresholded != expected), 0) << t;
  }
}

TEST(Segmentation, CurveEqualsBoundaryScoresPerThreshold) {
  const GridScene s = gridScene();
  const cv::Mat ucm = ultrametricContourMap(s.labels, s.ucg, s.mask);
  const std::vector<float> thresholds = {-1.0f, 0.0f, 0.3f, 0.5f, 0.7f, 0.9f, 2.0f};
  for (int tolerance : {0, 2}) {
    const std::vector<metrics::BoundaryCounts> curve =
        metrics::boundaryCurve(ucm, s.truth, s.mask, thresholds, tolerance);
    ASSERT_EQ(curve.size(), thresholds.size());
    for (std::size_t i = 0; i < thresholds.size(); ++i) {
      const cv::Mat segments = segmentPixels(s.labels, segmentGraph(s.ucg, thresholds[i]));
      const metrics::BoundaryScores expected =
          metrics::boundaryScores(segments, s.truth, s.mask, tolerance);
      EXPECT_EQ(curve[i].partition_pixels, expected.partition_boundary_pixels);
      EXPECT_EQ(curve[i].reference_pixels, expected.reference_boundary_pixels);
      EXPECT_DOUBLE_EQ(curve[i].precision(), expected.precision) << thresholds[i];
      EXPECT_DOUBLE_EQ(curve[i].recall(), expected.recall) << thresholds[i];
      EXPECT_DOUBLE_EQ(curve[i].f1(), expected.f1) << thresholds[i];
    }
  }
}

TEST(Sdasp, TwoObjectsGiveTwoSegments) {
  // Two boxes side by side at 0.9 m and 1.3 m, same grey, nothing valid around them.
  const RgbdFrame frame = test::twoBoxes();
  DaspConfig dasp_config;
  dasp_config.superpixel_count = 150;
  const Superpixels sp = computeDasp(frame, dasp_config);
  const WeightedGraph ucg = ultrametricContourGraph(sp);
  const cv::Mat segments = segmentPixels(sp.labels, segmentGraph(ucg, 0.5f));
  // Every labelled pixel of each box carries that box's majority segment; two segments in all.
  std::map<int, int> left, right;
  for (int y = 20; y < 100; ++y) {
    for (int x = 20; x < 140; ++x) {
      const int s = segments.at<int>(y, x);
      if (s >= 0) ++(x < 80 ? left : right)[s];
    }
  }
  auto majority = [](const std::map<int, int>& votes, double* share) {
    int best = -1, best_count = 0, total = 0;
    for (const auto& [s, c] : votes) {
      total += c;
      if (c > best_count) best = s, best_count = c;
    }
    *share = static_cast<double>(best_count) / total;
    return best;
  };
  double left_share = 0.0, right_share = 0.0;
  const int left_segment = majority(left, &left_share);
  const int right_segment = majority(right, &right_share);
  EXPECT_NE(left_segment, right_segment);
  EXPECT_GT(left_share, 0.97);
  EXPECT_GT(right_share, 0.97);
  EXPECT_EQ(metrics::countSegments(segments, cv::Mat()), 2u);
}

// Majority segment of the labelled pixels where `region` is non-zero, and its share of them.
int majoritySegment(const cv::Mat& segments, const cv::Mat& region, double* share) {
  std::map<int, int> votes;
  int total = 0;
  for (int y = 0; y < segments.rows; ++y) {
    for (int x = 0; x < segments.cols; ++x) {
      const int s = segments.at<int>(y, x);
      if (s < 0 || region.at<std::uint8_t>(y, x) == 0) continue;
      ++votes[s];
      ++total;
    }
  }
  int best = -1, best_count = 0;
  for (const auto& [s, c] : votes) {
    if (c > best_count) best = s, best_count = c;
  }
  *share = total == 0 ? 0.0 : static_cast<double>(best_count) / total;
  return best;
}

// s-DASP at the library defaults (DASP K = 1000, seed 0, then SdaspConfig{}).
cv::Mat sdaspSegments(const RgbdFrame& frame, const SdaspConfig& config = {}) {
  DaspConfig dasp_config;
  dasp_config.superpixel_count = 1000;
  const Superpixels sp = computeDasp(frame, dasp_config);
  const WeightedGraph ucg = ultrametricContourGraph(sp, config);
  return segmentPixels(sp.labels, segmentGraph(ucg, cutThreshold(ucg, config)));
}

// Every labelled region 1..regions of `labels` has a majority segment of its own holding more
// than 90 % of its pixels.
void expectOneSegmentPerRegion(const cv::Mat& segments, const cv::Mat& labels, int regions) {
  std::set<int> seen;
  for (int region = 1; region <= regions; ++region) {
    double share = 0.0;
    const int segment = majoritySegment(segments, labels == region, &share);
    EXPECT_GT(share, 0.9) << "region " << region;
    EXPECT_TRUE(seen.insert(segment).second) << "region " << region << " shares a segment";
  }
}

TEST(Sdasp, ThinFlatObjectOnATableIsItsOwnSegment) {
  // A 3 mm thin mat on a table (OSD-like frame, 640x480): its depth step is 3 quanta, so the
  // colour edge (eq. 4.19) must carry the boundary; a box stands beside it.
  cv::Mat labels;
  const RgbdFrame frame = test::thinObjectOnTable(&labels);
  expectOneSegmentPerRegion(sdaspSegments(frame), labels, 3);
}

TEST(Sdasp, TouchingBoxesAreSeparateSegments) {
  // Four boxes of four colours in a touching 2 x 2 cluster on the table: every box and the table
  // a segment of its own.
  cv::Mat labels;
  const RgbdFrame frame = test::touchingBoxes(&labels);
  expectOneSegmentPerRegion(sdaspSegments(frame), labels, 5);
}

TEST(Sdasp, CutThresholdFollowsTheRule) {
  // A path 0-1-2-3-4 with weights 0.01, 0.02, 0.03, 0.4 and a chord 0-2 of 0.5 that is not in
  // the minimum spanning tree: merge levels 0.01, 0.02, 0.03, 0.4.
  WeightedGraph graph;
  graph.node_count = 5;
  graph.edges = {{0, 1, 0.01f}, {0, 2, 0.5f}, {1, 2, 0.02f}, {2, 3, 0.03f}, {3, 4, 0.4f}};
  EXPECT_EQ(spanningMergeLevels(graph), (std::vector<float>{0.01f, 0.02f, 0.03f, 0.4f}));
  SdaspConfig config;
  config.cut = CutRule::kGlobal;
  config.threshold = 0.123f;
  EXPECT_FLOAT_EQ(cutThreshold(graph, config), 0.123f);
  config.cut = CutRule::kAdaptive;
  config.adaptive_scale = 2.0f;
  config.adaptive_quantile = 0.5f;  // between 0.02 and 0.03: 0.025
  config.adaptive_max_threshold = 1.0f;
  EXPECT_NEAR(cutThreshold(graph, config), 0.05f, 1e-6f);
  config.adaptive_quantile = 0.0f;
  EXPECT_NEAR(cutThreshold(graph, config), 0.02f, 1e-6f);
  config.adaptive_quantile = 1.0f;  // 2 x 0.4, capped
  config.adaptive_max_threshold = 0.25f;
  EXPECT_FLOAT_EQ(cutThreshold(graph, config), 0.25f);
  // The cut the rule picks splits the graph at the weak link only.
  config.adaptive_quantile = 0.5f;
  const std::vector<int> nodes = segmentGraph(graph, cutThreshold(graph, config));
  EXPECT_EQ(nodes, (std::vector<int>{0, 0, 0, 0, 1}));
  // No edges: the upper bound.
  EXPECT_FLOAT_EQ(cutThreshold(WeightedGraph{3, {}}, config), 0.25f);
  config.adaptive_scale = 0.0f;
  EXPECT_THROW(cutThreshold(graph, config), std::invalid_argument);
  config.adaptive_scale = 2.0f;
  config.adaptive_quantile = 1.5f;
  EXPECT_THROW(cutThreshold(graph, config), std::invalid_argument);
  config.adaptive_quantile = 0.5f;
  config.adaptive_max_threshold = 0.0f;
  EXPECT_THROW(cutThreshold(graph, config), std::invalid_argument);
  config.cut = CutRule::kGlobal;
  config.threshold = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(cutThreshold(graph, config), std::invalid_argument);
}

}  // namespace
}  // namespace dasp

// Tests of t-DASP (thesis ch. 5): Delta Density Sampling, streaming DASP, strands, hysteresis
// segmentation, the temporal consistency metric and the whole pipeline.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "dasp/delta_density.h"
#include "dasp/hysteresis_segmentation.h"
#include "dasp/metrics.h"
#include "dasp/sampling.h"
#include "dasp/strands.h"
#include "dasp/streaming_dasp.h"
#include "dasp/tdasp.h"
#include "dasp/temporal_metrics.h"
#include "dasp_synthetic.h"

namespace dasp {
namespace {

cv::Mat constantDensity(int width, int height, float value) {
  return cv::Mat(height, width, CV_32FC1, cv::Scalar(value));
}

// A table-top-like scene: a background plane and three boxes of distinct colours at distinct
// depths, with Kinect-like depth noise and colour noise drawn from `noise_seed`. The boxes are
// shifted by shift_px columns (a moving scene).
RgbdFrame boxScene(int width, int height, std::uint64_t noise_seed, int shift_px = 0) {
  RgbdFrame frame;
  frame.intrinsics = test::syntheticIntrinsics(width, height);
  frame.color = cv::Mat(height, width, CV_8UC3, cv::Scalar(200, 200, 200));
  frame.depth = cv::Mat(height, width, CV_16UC1, cv::Scalar(1500));
  const cv::Rect boxes[3] = {cv::Rect(width / 8, height / 4, width / 5, height / 2),
                             cv::Rect(2 * width / 5, height / 5, width / 5, height / 3),
                             cv::Rect(7 * width / 10, height / 2, width / 5, height / 3)};
  const cv::Scalar colours[3] = {cv::Scalar(30, 30, 200), cv::Scalar(40, 180, 40),
                                 cv::Scalar(190, 60, 20)};
  const int depths[3] = {900, 1100, 1000};
  for (int i = 0; i < 3; ++i) {
    cv::Rect r = boxes[i];
    r.x = std::clamp(r.x + shift_px, 0, width - r.width);
    frame.color(r).setTo(colours[i]);
    frame.depth(r).setTo(depths[i]);
  }
  std::mt19937_64 rng(noise_seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::uint16_t& d = frame.depth.at<std::uint16_t>(y, x);
      const double z = d / 1000.0;
      const double sigma = 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4);
      d = static_cast<std::uint16_t>(std::lround((z + sigma * normal(rng)) * 1000.0));
      cv::Vec3b& c = frame.color.at<cv::Vec3b>(y, x);
      for (int ch = 0; ch < 3; ++ch)
        c[ch] = cv::saturate_cast<std::uint8_t>(c[ch] + 3 * normal(rng));
    }
  }
  return frame;
}

TEST(DeltaDensity, RealizedDensityIntegratesToThePointCount) {
  const cv::Mat density = constantDensity(120, 90, 0.01f);
  const std::vector<Seed> points = sampleSpds(density, true, 3);
  const cv::Mat realized = realizedDensity(density, points);
  EXPECT_NEAR(cv::sum(realized)[0], static_cast<double>(points.size()), 1e-2 * points.size());
}

TEST(DeltaDensity, NearestPointIndexMatchesBruteForce) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 200.0f), v(0.0f, 100.0f);
  std::vector<Seed> points(300);
  for (Seed& p : points) p = {u(rng), v(rng)};
  NearestPointIndex index(points, 200, 100, 9.0f);
  std::vector<std::uint8_t> removed(points.size(), 0);
  for (int q = 0; q < 300; ++q) {
    const float qu = u(rng), qv = v(rng);
    float best = 1e30f;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (removed[i]) continue;
      best = std::min(best, std::hypot(points[i].u - qu, points[i].v - qv));
    }
    const int got = index.removeNearest(qu, qv);
    ASSERT_GE(got, 0);
    ASSERT_FALSE(removed[static_cast<std::size_t>(got)]);
    EXPECT_FLOAT_EQ(std::hypot(points[static_cast<std::size_t>(got)].u - qu,
                               points[static_cast<std::size_t>(got)].v - qv),
                    best);
    removed[static_cast<std::size_t>(got)] = 1;
  }
  EXPECT_EQ(index.remaining(), 0);
  EXPECT_EQ(index.removeNearest(5.0f, 5.0f), -1);
}

TEST(DeltaDensity, KeepsPointsWhereTheDensityDidNotChange) {
  const int width = 160, height = 120;
  const cv::Mat density = constantDensity(width, height, 0.01f);  // 192 points
  const std::vector<Seed> points = sampleSpds(density, true, 11);
  const DeltaDensityResult same = deltaDensitySampling(density, points, {}, 5);
  int kept = 0;
  for (const int o : same.origin) kept += o >= 0 ? 1 : 0;
  EXPECT_GE(kept, static_cast<int>(0.9 * points.size()));
  EXPECT_LE(same.added + same.removed_by_density, static_cast<int>(0.1 * points.size()));

  // Double the density in the left half: the right half keeps its points, the left half gains.
  cv::Mat changed = density.clone();
  changed(cv::Rect(0, 0, width / 2, height)).setTo(0.02f);
  const DeltaDensityResult grown = deltaDensitySampling(changed, points, {}, 6);
  int right_before = 0, right_kept = 0, left_before = 0, left_after = 0;
  for (const Seed& p : points) (p.u < width / 2 ? left_before : right_before)++;
  for (std::size_t i = 0; i < grown.points.size(); ++i) {
    const Seed& p = grown.points[i];
    if (p.u < width / 2 - 10) ++left_after;
    if (p.u >= width / 2 + 10 && grown.origin[i] >= 0) ++right_kept;
  }
  int right_far_before = 0;
  for (const Seed& p : points) right_far_before += p.u >= width / 2 + 10 ? 1 : 0;
  EXPECT_GE(right_kept, static_cast<int>(0.9 * right_far_before));
  EXPECT_GT(left_after, static_cast<int>(1.6 * (left_before - 0.125 * left_before)));
}

TEST(DeltaDensity, PointCountMatchesTheDensityIntegral) {
  const int width = 160, height = 120;
  const cv::Mat before = constantDensity(width, height, 0.01f);
  cv::Mat after = before.clone();
  after(cv::Rect(0, 0, width / 2, height)).setTo(0.02f);           // +96
  after(cv::Rect(width / 2, 0, width / 4, height)).setTo(0.004f);  // -29
  const double target = cv::sum(after)[0];
  double mean_count = 0.0;
  const int runs = 12;
  for (int run = 0; run < runs; ++run) {
    const std::vector<Seed> points = sampleSpds(before, true, 100 + run);
    const DeltaDensityResult r = deltaDensitySampling(after, points, {}, 200 + run);
    mean_count += static_cast<double>(r.points.size()) / runs;
    EXPECT_NEAR(r.positive_mass - r.negative_mass, target - points.size(), 1e-2 * target);
  }
  EXPECT_NEAR(mean_count, target, 0.03 * target);
}

TEST(DeltaDensity, DropsPointsOnPixelsWithoutDensity) {
  cv::Mat density = constantDensity(100, 100, 0.01f);
  const std::vector<Seed> points = {{10, 10}, {50, 50}, {90, 90}};
  density(cv::Rect(0, 0, 30, 30)).setTo(0.0f);
  const DeltaDensityResult r = deltaDensitySampling(density, points, {}, 1);
  EXPECT_EQ(r.removed_invalid, 1);
  for (std::size_t i = 0; i < r.points.size(); ++i) EXPECT_NE(r.origin[i], 0);
  EXPECT_THROW(deltaDensitySampling(density, points, {SeedingMethod::kGrid}, 1),
               std::invalid_argument);
}

TEST(StreamingDasp, KeepsIdsOverARepeatedFrame) {
  StreamingDaspConfig config;
  config.dasp.superpixel_count = 150;
  StreamingDasp stream(config);
  const StreamingDaspFrame first = stream.process(boxScene(160, 120, 1));
  EXPECT_TRUE(std::all_of(first.predecessor.begin(), first.predecessor.end(),
                          [](int p) { return p == -1; }));
  std::set<std::int64_t> first_ids(first.track_id.begin(), first.track_id.end());
  EXPECT_EQ(first_ids.size(), first.track_id.size());
  StreamingDaspFrame previous = first;
  for (int k = 1; k < 5; ++k) {
    const StreamingDaspFrame next = stream.process(boxScene(160, 120, 1 + k));
    ASSERT_EQ(next.predecessor.size(), next.superpixels.superpixels.size());
    int linked = 0, near = 0;
    std::set<int> used;
    for (std::size_t j = 0; j < next.predecessor.size(); ++j) {
      const int p = next.predecessor[j];
      if (p < 0) continue;
      ++linked;
      EXPECT_TRUE(used.insert(p).second) << "predecessor used twice";
      EXPECT_EQ(next.track_id[j], previous.track_id[static_cast<std::size_t>(p)]);
      const Superpixel& a = next.superpixels.superpixels[j];
      const Superpixel& b = previous.superpixels.superpixels[static_cast<std::size_t>(p)];
      // R_rho = 1 / sqrt(pi 150 / (160 * 120)) = 6.4 px: DALIC moves most centres much less.
      near += std::hypot(a.u - b.u, a.v - b.v) < 6.4f ? 1 : 0;
    }
    EXPECT_GE(linked, static_cast<int>(0.85 * next.predecessor.size()));
    EXPECT_GE(near, static_cast<int>(0.9 * linked));
    previous = next;
  }
  // Ids of the first frame still alive after four frames of noise.
  int alive = 0;
  for (const std::int64_t id : previous.track_id) alive += first_ids.count(id) ? 1 : 0;
  EXPECT_GE(alive, static_cast<int>(0.6 * previous.track_id.size()));
}

TEST(Strands, PlausibilityPrunesImplausibleContinuations) {
  Superpixel a;
  a.color = Eigen::Vector3f(0.5f, 0.5f, 0.5f);
  a.position = Eigen::Vector3f(0.0f, 0.0f, 1.0f);
  a.normal = Eigen::Vector3f(0.0f, 0.0f, -1.0f);
  a.radius_m = 0.02f;
  const StrandConfig config;
  Superpixel b = a;
  EXPECT_TRUE(plausibleContinuation(a, b, config));
  b.color = Eigen::Vector3f(0.9f, 0.5f, 0.5f);
  EXPECT_FALSE(plausibleContinuation(a, b, config));
  b = a;
  b.position.z() += 0.1f;  // 5 R
  EXPECT_FALSE(plausibleContinuation(a, b, config));
  b = a;
  b.normal = Eigen::Vector3f(1.0f, 0.0f, 0.0f);
  EXPECT_FALSE(plausibleContinuation(a, b, config));
}

TEST(Strands, StrandGraphAveragesWeightsOverTheCommonLifetime) {
  // Two superpixels per frame, linked over three frames; the edge weight changes per frame.
  StrandGraph graph;
  StreamingDaspFrame frame;
  frame.superpixels.superpixels.resize(2);
  for (auto& s : frame.superpixels.superpixels) s.radius_m = 0.02f;
  frame.predecessor = {-1, -1};
  const float weights[3] = {0.9f, 0.6f, 0.0f};
  for (int k = 0; k < 3; ++k) {
    WeightedGraph g;
    g.node_count = 2;
    if (weights[k] > 0.0f) g.edges.push_back({0, 1, weights[k]});
    graph.addFrame(frame, g);
    frame.predecessor = {0, 1};
  }
  ASSERT_EQ(graph.strands().size(), 2u);
  const WeightedGraph g = graph.graph();
  ASSERT_EQ(g.edges.size(), 1u);
  EXPECT_NEAR(g.edges[0].weight, (0.9f + 0.6f + 0.0f) / 3.0f, 1e-6);  // eq. 5.12: |t_pq| = 3
}

TEST(Strands, StrandCountStaysBounded) {
  StrandConfig config;
  config.max_strands = 200;  // 150 superpixels per frame
  StrandGraph graph(config);
  StreamingDaspConfig sc;
  sc.dasp.superpixel_count = 150;
  StreamingDasp stream(sc);
  std::size_t max_edges = 0;
  for (int k = 0; k < 12; ++k) {
    // A moving scene: strands end and start every frame.
    const StreamingDaspFrame f = stream.process(boxScene(160, 120, 50 + k, 3 * k));
    graph.addFrame(f, buildSuperpixelGraph(f.superpixels, config.graph));
    EXPECT_LE(static_cast<int>(graph.strands().size()), config.max_strands);
    const WeightedGraph g = graph.graph();
    for (const GraphEdge& e : g.edges) {
      ASSERT_LT(e.a, g.node_count);
      ASSERT_LT(e.b, g.node_count);
    }
    max_edges = std::max(max_edges, g.edges.size());
  }
  EXPECT_EQ(static_cast<int>(graph.strands().size()), config.max_strands);
  EXPECT_LT(max_edges, static_cast<std::size_t>(10 * config.max_strands));
}

TEST(Hysteresis, ThreeThresholdsDependOnSupervision) {
  HysteresisConfig config;
  config.force = 0.04f;
  config.normal = 0.08f;
  config.grant = 0.16f;
  WeightedGraph g;
  g.node_count = 6;
  g.edges = {{0, 1, 0.12f},   // same supervised label: granted
             {1, 2, 0.06f},   // different supervised labels: above t_force, kept apart
             {2, 3, 0.06f},   // one unsupervised: normal merge
             {3, 4, 0.12f},   // unsupervised: above t_normal
             {4, 5, 0.02f}};  // forced
  const std::vector<std::int64_t> supervised = {7, 7, 9, -1, 11, 12};
  std::int64_t next = 20;
  const HysteresisResult r = hysteresisSegmentation(g, supervised, {}, config, next);
  EXPECT_EQ(r.labels[0], 7);
  EXPECT_EQ(r.labels[1], 7);
  EXPECT_EQ(r.labels[2], 9);
  EXPECT_EQ(r.labels[3], 9);  // joined the supervised segment 9
  EXPECT_NE(r.labels[4], r.labels[3]);
  EXPECT_EQ(r.labels[4], r.labels[5]);
  EXPECT_TRUE(r.labels[4] == 11 || r.labels[4] == 12);
  EXPECT_EQ(r.component_count, 3);
  // A new node similar to two different supervised segments joins one of them but does not
  // bridge them (the rules use the labels of the segments merged so far).
  g.node_count = 3;
  g.edges = {{0, 1, 0.05f}, {1, 2, 0.06f}};
  const HysteresisResult bridge = hysteresisSegmentation(g, {1, -1, 2}, {}, config, next);
  EXPECT_EQ(bridge.labels[0], 1);
  EXPECT_EQ(bridge.labels[1], 1);
  EXPECT_EQ(bridge.labels[2], 2);
  g.node_count = 6;
  // A supervised segment that falls apart keeps its label on the larger piece only.
  g.edges = {};
  const HysteresisResult split =
      hysteresisSegmentation(g, {5, 5, 5, -1, -1, -1}, {1, 3, 1, 1, 1, 1}, config, next);
  EXPECT_EQ(split.labels[1], 5);
  EXPECT_NE(split.labels[0], 5);
  EXPECT_NE(split.labels[2], 5);
  EXPECT_GE(split.labels[0], 20);
  EXPECT_THROW(hysteresisSegmentation(g, {1}, {}, config, next), std::invalid_argument);
}

TEST(TemporalConsistency, WarpsWithDepthAndPose) {
  const int width = 80, height = 60;
  const Intrinsics in = test::syntheticIntrinsics(width, height);
  cv::Mat depth(height, width, CV_16UC1, cv::Scalar(1000));
  cv::Mat labels(height, width, CV_32SC1, cv::Scalar(0));
  labels(cv::Rect(0, 0, width / 2, height)).setTo(1);
  // The camera moves by 2 cm along x: the scene shifts by 200 * 0.02 / 1 = 4 px to the left.
  Eigen::Isometry3f next_from_current = Eigen::Isometry3f::Identity();
  next_from_current.translation() = Eigen::Vector3f(-0.02f, 0.0f, 0.0f);
  cv::Mat shifted(height, width, CV_32SC1, cv::Scalar(0));
  shifted(cv::Rect(0, 0, width / 2 - 4, height)).setTo(1);
  const auto exact = metrics::temporalLabelConsistency(
      labels, depth, shifted, depth, in, next_from_current, metrics::LabelMatching::kIdentity);
  EXPECT_GT(exact.compared, 0u);
  EXPECT_DOUBLE_EQ(exact.consistency, 1.0);
  const auto unshifted = metrics::temporalLabelConsistency(
      labels, depth, labels, depth, in, next_from_current, metrics::LabelMatching::kIdentity);
  EXPECT_LT(unshifted.consistency, 0.95);
  // Renamed labels: identity fails, best-overlap matching recovers them.
  cv::Mat renamed = shifted + 5;
  EXPECT_DOUBLE_EQ(
      metrics::temporalLabelConsistency(labels, depth, renamed, depth, in, next_from_current,
                                        metrics::LabelMatching::kIdentity)
          .consistency,
      0.0);
  EXPECT_DOUBLE_EQ(
      metrics::temporalLabelConsistency(labels, depth, renamed, depth, in, next_from_current,
                                        metrics::LabelMatching::kBestOverlap)
          .consistency,
      1.0);
}

TEST(Tdasp, LabelsPersistOverAStaticFrameWithSensorNoise) {
  TdaspConfig config;
  config.superpixels.dasp.superpixel_count = 200;
  TemporalDasp tdasp(config);
  const int width = 160, height = 120;
  TdaspFrame previous = tdasp.process(boxScene(width, height, 1000));
  const cv::Mat first_labels = previous.segment_labels.clone();
  EXPECT_GE(metrics::countSegments(first_labels, cv::Mat()), 3u);
  const Eigen::Isometry3f identity = Eigen::Isometry3f::Identity();
  const Intrinsics in = test::syntheticIntrinsics(width, height);
  for (int k = 1; k < 8; ++k) {
    const RgbdFrame frame = boxScene(width, height, 1000 + k);
    const TdaspFrame next = tdasp.process(frame);
    const auto c = metrics::temporalLabelConsistency(previous.segment_labels, frame.depth,
                                                     next.segment_labels, frame.depth, in, identity,
                                                     metrics::LabelMatching::kIdentity);
    EXPECT_GT(c.consistency, 0.97) << "frame " << k;
    EXPECT_LE(next.strand_count, config.strands.max_strands);
    previous = next;
  }
  // After seven noisy frames the labels are still those of the first frame.
  int same = 0, total = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (first_labels.at<int>(y, x) < 0 || previous.segment_labels.at<int>(y, x) < 0) continue;
      ++total;
      same += first_labels.at<int>(y, x) == previous.segment_labels.at<int>(y, x) ? 1 : 0;
    }
  }
  EXPECT_GT(same, 0.95 * total);
}

}  // namespace
}  // namespace dasp

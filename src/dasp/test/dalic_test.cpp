// Dalic::assign() against a brute-force search: every pixel to the nearest cluster whose reach
// disc (radius C R + 1 px around the centre) holds it, over all clusters, on image sizes whose
// rows do not split evenly into the assignment's row stripes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dasp/dalic.h"
#include "dasp/density.h"
#include "dasp/features.h"
#include "dasp/sampling.h"
#include "dasp_synthetic.h"
#include "simd.h"

namespace dasp {
namespace {

// The full distance of alg. 3 / eq. 3.19-3.21 (not the reduced form assign() evaluates).
float fullDistance(const PixelFeatures& f, const DalicParams& p, const Cluster& c, int x, int y) {
  const std::size_t i = static_cast<std::size_t>(y) * f.width + x;
  const Eigen::Vector3f color(f.r[i], f.g[i], f.b[i]);
  float d = p.weight_color * (color - c.color).squaredNorm();
  if (p.metric == MetricKind::kDepthAdaptive) {
    const Eigen::Vector3f point(f.x[i], f.y[i], f.z[i]);
    const Eigen::Vector3f normal(f.nx[i], f.ny[i], f.nz[i]);
    // Each cluster's own radius (DaspExperimental::depth_exponent; radius_m for the thesis' 2).
    const float radius = radiusAtDepth(p.radius_m, c.position.z(), p.depth_exponent);
    d += p.weight_spatial / (radius * radius) * (point - c.position).squaredNorm() +
         p.weight_normal * (1.0f - normal.dot(c.normal));
  } else {
    const float du = static_cast<float>(x) - c.u, dv = static_cast<float>(y) - c.v;
    d += p.weight_spatial / (c.radius_px * c.radius_px) * (du * du + dv * dv);
  }
  return d;
}

// The rounding error of the reduced d_DA that assign() evaluates for pixel i against clusters a
// and b (ClusterTerms): its terms, up to weight (1 + weight_depth) (|p|^2 + |p_i|^2) / R^2 in
// size, cancel to a distance of order 1, so the error is a few float epsilons of that size
// (about 1e-3 at 1.4 m with R = 4 cm). How the compiler orders and contracts the
// sums (-O0 or optimised) decides which of two clusters that near wins.
float reducedFormRounding(const PixelFeatures& f, const DalicParams& p, const Cluster& a,
                          const Cluster& b, std::size_t i) {
  if (p.metric != MetricKind::kDepthAdaptive) return 0.0f;
  const float p2 = f.x[i] * f.x[i] + f.y[i] * f.y[i] + f.z[i] * f.z[i];
  float size = 0.0f;
  for (const Cluster* c : {&a, &b}) {
    const float radius = radiusAtDepth(p.radius_m, c->position.z(), p.depth_exponent);
    size = std::max(size, p.weight_spatial * (1.0f + p.weight_depth) *
                              (p2 + c->position.squaredNorm()) / (radius * radius));
  }
  return 8.0f * std::numeric_limits<float>::epsilon() * size;
}

struct Comparison {
  int pixels = 0;      // valid pixels compared
  int ambiguous = 0;   // skipped: some cluster's disc edge passes through the pixel
  int mismatches = 0;  // labels differ and the distances are not equal within rounding
  int assigned = 0;    // pixels the reference gives a cluster
};

// Runs two DALIC iterations (so the clusters have moved off the seeds), assigns once more and
// compares the labels with the brute-force nearest cluster.
Comparison compareWithBruteForce(const PixelFeatures& f, const cv::Mat& density,
                                 const DalicParams& params, std::uint64_t seed) {
  Dalic dalic(f, density, params);
  dalic.initialize(sampleSeeds(density, SeedingMethod::kSpdsImproved, seed));
  dalic.iterate();
  dalic.iterate();
  const std::vector<Cluster> clusters = dalic.clusters();
  dalic.assign();
  const cv::Mat labels = dalic.labels();
  Comparison result;
  for (int y = 0; y < f.height; ++y) {
    for (int x = 0; x < f.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * f.width + x;
      if (!f.valid[i]) {
        EXPECT_EQ(labels.at<int>(y, x), -1);
        continue;
      }
      ++result.pixels;
      int best = -1;
      float best_distance = std::numeric_limits<float>::max();
      bool ambiguous = false;
      for (std::size_t k = 0; k < clusters.size(); ++k) {
        const Cluster& c = clusters[k];
        const float reach = params.window_multiple * c.radius_px + 1.0f;
        const float du = static_cast<float>(x) - c.u, dv = static_cast<float>(y) - c.v;
        const float r2 = du * du + dv * dv;
        if (std::abs(r2 - reach * reach) <= 1e-3f * reach * reach) ambiguous = true;
        if (r2 > reach * reach) continue;
        const float d = fullDistance(f, params, c, x, y);
        if (d < best_distance) {
          best_distance = d;
          best = static_cast<int>(k);
        }
      }
      if (ambiguous) {
        ++result.ambiguous;
        continue;
      }
      result.assigned += best >= 0;
      const int got = labels.at<int>(y, x);
      if (got == best) continue;
      const bool equally_near =
          got >= 0 && best >= 0 &&
          std::abs(fullDistance(f, params, clusters[static_cast<std::size_t>(got)], x, y) -
                   best_distance) <=
              1e-4f * std::max(1.0f, best_distance) +
                  reducedFormRounding(f, params, clusters[static_cast<std::size_t>(got)],
                                      clusters[static_cast<std::size_t>(best)], i);
      if (!equally_near) ++result.mismatches;
    }
  }
  return result;
}

// Random colours: the colour term separates the clusters everywhere, so few pixels tie.
cv::Mat randomColor(int width, int height, std::uint64_t seed) {
  cv::Mat color(height, width, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(color, cv::RNG::UNIFORM, 0, 256);
  return color;
}

TEST(DalicAssign, Color2DMatchesBruteForceNearestCluster) {
  // 61 rows: stripes of 3 and 4 rows; K from superpixels much larger than a stripe to tiny ones.
  const PixelFeatures f = computeColorFeatures(randomColor(173, 61, 3));
  for (int count : {12, 150, 900}) {
    DalicParams params;
    params.metric = MetricKind::kColor2D;
    params.weight_color = 100.0f;
    const Comparison c = compareWithBruteForce(f, computeConstantDensity(f, count), params, 5);
    EXPECT_EQ(c.mismatches, 0) << "K = " << count;
    EXPECT_LT(c.ambiguous, c.pixels / 20) << "K = " << count;
    EXPECT_GT(c.assigned, c.pixels * 9 / 10) << "K = " << count;
  }
}

TEST(DalicAssign, DepthAdaptiveMatchesBruteForceNearestCluster) {
  // A slanted plane (superpixel sizes vary down the image) with a hole of invalid depth. The
  // eight-lane loop and, on a processor with AVX-512, the sixteen-lane one (masked at the row
  // end: the width is no multiple of 16).
  RgbdFrame frame = test::slantedPlane(150, 107, 1.8f, 0.8f);
  frame.color = randomColor(150, 107, 4);
  frame.depth(cv::Rect(40, 30, 25, 20)).setTo(0);
  const DaspConfig config;
  const PixelFeatures f = computeFeatures(frame, config);
  for (bool sixteen_lanes : {false, true}) {
#if DASP_AVX512_FUNCTIONS
    detail::avx512Allowed() = sixteen_lanes;
#else
    if (sixteen_lanes) continue;  // no AVX-512 loop in this build
#endif
    // Depth exponent 1: a radius per cluster (the pixel's own |p|^2 terms stay in the distance).
    for (const float exponent : {2.0f, 1.0f})
      for (int count : {20, 300}) {
        DalicParams params;
        params.depth_exponent = exponent;
        params.radius_m = radiusForCount(f, count, exponent);
        const cv::Mat density = computeDepthDensity(f, params.radius_m, exponent);
        for (int threads : {1, 0}) {
          params.threads = threads;
          const Comparison c = compareWithBruteForce(f, density, params, 9);
          const std::string where = "K = " + std::to_string(count) +
                                    ", depth exponent = " + std::to_string(exponent) +
                                    ", threads = " + std::to_string(threads) +
                                    (sixteen_lanes ? ", AVX-512 allowed" : ", eight lanes");
          EXPECT_EQ(c.mismatches, 0) << where;
          EXPECT_LT(c.ambiguous, c.pixels / 20) << where;
          EXPECT_GT(c.assigned, c.pixels * 9 / 10) << where;
        }
      }
  }
}

}  // namespace
}  // namespace dasp

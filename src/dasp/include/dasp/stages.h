// The individual stages of Adaptive Superpixels and Depth-Adaptive Superpixels, public so that
// tests, benchmarks and experiments can run and time each one (see dasp/dasp.h for the
// one-call entry points and the conventions).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "dasp/dasp.h"
#include "dasp/pixel_allocator.h"

namespace dasp {

/// Per-pixel features in structure-of-arrays layout (index = row * width + column).
/// Colour-only features (computeColorFeatures) leave the 3D arrays empty.
struct PixelFeatures {
  int width = 0;
  int height = 0;
  Intrinsics intrinsics;
  PixelVector<float> r, g, b;     ///< Colour in [0, 1].
  PixelVector<float> x, y, z;     ///< 3D point (eq. 3.4), metres, optical frame; 0 if invalid.
  PixelVector<float> nx, ny, nz;  ///< Unit normal towards the camera (eq. 3.8, 3.9); 0 if invalid.
  /// 3D surface area seen by the pixel, m^2: (z^2 / (fx fy)) times the slant factor, the
  /// perspective form of sqrt(|grad D|^2 + 1) in eq. 3.14/3.15, clamped to max_slant_factor.
  PixelVector<float> area;
  PixelVector<std::uint8_t> valid;  ///< 1 where depth (or, colour only, the pixel) is usable.
  int valid_count = 0;

  bool hasDepth() const { return !z.empty(); }
  std::size_t size() const { return static_cast<std::size_t>(width) * height; }
};

/// Checks a frame and the DASP parameters; throws std::invalid_argument with the reason.
/// Does not look at the depth values (computeFeatures reports "no valid depth").
void validateInput(const RgbdFrame& frame, const DaspConfig& config);

/// Stage 1 of alg. 4: colour, 3D points and normals from robust finite differences of depth
/// (eq. 3.4, 3.6-3.10) and the per-pixel 3D area for the density. Throws if no pixel has depth.
PixelFeatures computeFeatures(const RgbdFrame& frame, const DaspConfig& config = {});
/// The same into `features`, reusing its storage: a stream of same-sized frames allocates nothing.
void computeFeatures(const RgbdFrame& frame, const DaspConfig& config, PixelFeatures& features);

/// Colour-only features of a CV_8UC3 BGR image; every pixel valid.
PixelFeatures computeColorFeatures(const cv::Mat& color);

/// Superpixel radius R (metres) for which the depth-adaptive density integrates to `count`
/// over the valid pixels (eq. 3.17): R = sqrt(sum area (z / 1 m)^(a - 2) / (pi count)), a the
/// depth exponent (DaspConfig::depth_exponent; 2: the thesis, R = sqrt(sum area / (pi count))).
float radiusForCount(const PixelFeatures& features, int count, float depth_exponent = 2.0f);

/// The 3D superpixel radius at depth z for the radius R at 1 m and the depth exponent a:
/// R (z / 1 m)^((2 - a) / 2); R itself for a = 2 (every depth) or z <= 0.
float radiusAtDepth(float radius_m, float depth_m, float depth_exponent);

/// Depth-adaptive density (eq. 3.15): rho(u) = area(u) (z / 1 m)^(a - 2) / (pi R^2)
/// superpixels per pixel (a = 2: area / (pi R^2)), 0 where depth is invalid. CV_32FC1.
/// depth_exponent: one of 0, 0.5, 1, 1.5, 2 (else std::invalid_argument).
cv::Mat computeDepthDensity(const PixelFeatures& features, float radius_m,
                            float depth_exponent = 2.0f);
/// The same into `density`, reusing its storage when the size matches.
void computeDepthDensity(const PixelFeatures& features, float radius_m, cv::Mat& density,
                         float depth_exponent = 2.0f);

/// Constant density over the valid pixels that integrates to `count`. CV_32FC1.
cv::Mat computeConstantDensity(const PixelFeatures& features, int count);

/// Sum of all density values (the expected number of superpixels).
double densityIntegral(const cv::Mat& density);

/// A sampled superpixel centre in pixel coordinates.
struct Seed {
  float u = 0.0f;
  float v = 0.0f;
};

/// Density pyramid of eq. 2.7: level 0 is the density, level l+1 sums 2x2 blocks of level l
/// (images whose size is not a power of two are padded with zero density). The last level is
/// 1x1 and holds the integral.
class DensityPyramid {
 public:
  explicit DensityPyramid(const cv::Mat& density);
  int levels() const { return static_cast<int>(level_.size()); }
  const cv::Mat& level(int l) const { return level_[static_cast<std::size_t>(l)]; }  ///< CV_64F
  /// Mass of node (x, y) at level l; 0 outside the level.
  double mass(int l, int x, int y) const;

 private:
  std::vector<cv::Mat> level_;
};

/// Simplified Poisson Disc Sampling: alg. 1 (improved = false) or alg. 2 (improved = true).
/// density: CV_32FC1, >= 0, superpixels per pixel.
std::vector<Seed> sampleSpds(const cv::Mat& density, bool improved, std::uint64_t seed);
/// White-noise sampling: round(integral) independent draws with probability proportional to rho.
std::vector<Seed> sampleRandom(const cv::Mat& density, std::uint64_t seed);
/// Regular grid with spacing 1 / sqrt(mean positive density), points on positive density only.
std::vector<Seed> sampleGrid(const cv::Mat& density);
/// Dispatches on the method.
std::vector<Seed> sampleSeeds(const cv::Mat& density, SeedingMethod method, std::uint64_t seed);

/// The pixel-to-cluster distance used by DALIC.
enum class MetricKind {
  kDepthAdaptive,  ///< d_DA (eq. 3.19-3.21): colour, 3D position / R, normal (DASP).
  kColor2D,        ///< def. 7: colour + 2D distance / R_rho(cluster) (ASP, any 2D density).
  kColorDepth2D,   ///< Naive RGB-D: colour + 2D distance / R_rho + depth difference / R.
};

/// Parameters of one DALIC run (alg. 3).
struct DalicParams {
  MetricKind metric = MetricKind::kDepthAdaptive;
  float weight_spatial = 1.0f;
  float weight_color = 2.0f;
  float weight_normal = 3.0f;
  float weight_depth = 0.0f;  ///< kDepthAdaptive only, see DaspConfig::weight_depth.
  float window_multiple = 1.5f;
  float radius_m = 0.02f;  ///< R for kDepthAdaptive / kColorDepth2D (metres).
  /// kDepthAdaptive: DaspConfig::depth_exponent; a cluster at depth z has the radius
  /// radiusAtDepth(radius_m, z, depth_exponent) in d_DA and in its window.
  float depth_exponent = 2.0f;
  /// Purge clusters with fewer pixels than this fraction of their expected area 1/rho.
  float min_size_fraction = 0.1f;
  /// If > 0, after each update the number of clusters is brought to this value by splitting
  /// the clusters with the largest density mass or dropping the ones with the smallest.
  int target_count = 0;
  int threads = 1;  ///< 1 = single-threaded, 0 = all cores.
};

/// The radius R (metres, at 1 m for depth exponents other than 2) DASP uses for `config`:
/// radiusForCount(features, superpixel_count, depth_exponent) in count mode, radius_m in radius
/// mode.
float daspRadius(const PixelFeatures& features, const DaspConfig& config);

/// DALIC parameters of the RGB-D methods (DASP, streaming DASP, the naive ASP_RGBD baseline)
/// from one config: its weights, window, purge fraction and threads, with the given metric,
/// radius R (metres) and count-control target (0 = none).
DalicParams dalicParams(const DaspConfig& config, MetricKind metric, float radius_m,
                        int target_count);

/// A DALIC cluster (superpixel centre) and its mean features.
struct Cluster {
  float u = 0.0f, v = 0.0f;  ///< Centre, pixels.
  Eigen::Vector3f color = Eigen::Vector3f::Zero();
  Eigen::Vector3f position = Eigen::Vector3f::Zero();
  Eigen::Vector3f normal = -Eigen::Vector3f::UnitZ();
  float radius_px = 1.0f;  ///< Projected radius R_rho at the centre, pixels (window / C).
  int pixel_count = 0;
  float mass = 0.0f;  ///< Sum of the density over the cluster's pixels (ideally 1).
  float spread_u = 0.0f, spread_v = 0.0f;  ///< Principal 2D axis times its std dev, pixels.
  /// Index of the seed (in the vector given to Dalic::initialize) this cluster grew from; -1 for
  /// clusters created later by count-control splits. Streaming DASP links superpixels through it.
  int origin = -1;
};

/// Density-Adaptive Local Iterative Clustering (alg. 3). Holds its working buffers so that the
/// iterations allocate nothing. The features and density must outlive the object.
class Dalic {
 public:
  Dalic(const PixelFeatures& features, const cv::Mat& density, const DalicParams& params);
  ~Dalic();
  Dalic(const Dalic&) = delete;
  Dalic& operator=(const Dalic&) = delete;

  /// New parameters for the next run on the (possibly changed) features and density this object
  /// refers to; keeps the working buffers when the image size is unchanged. Call initialize next.
  void reset(const DalicParams& params);
  /// Clusters at the seeds, features averaged over a small neighbourhood (alg. 4).
  void initialize(const std::vector<Seed>& seeds);
  /// Assignment half of one iteration: each pixel to the nearest cluster whose window holds it.
  void assign();
  /// Update half: cluster means and plane-fit normals, purge of tiny clusters, count control.
  void update();
  /// assign() then update().
  void iterate() {
    assign();
    update();
  }

  const std::vector<Cluster>& clusters() const { return clusters_; }
  /// Labels of the last assign(), CV_32SC1 view of the internal buffer (-1 unassigned).
  cv::Mat labels() const;

 private:
  struct Impl;
  const PixelFeatures& features_;
  const cv::Mat& density_;
  DalicParams params_;
  std::vector<Cluster> clusters_;
  PixelVector<int> labels_;
  PixelVector<float> distance_;
  struct Scratch;  // working memory of initialize(), assign() and update(), kept across calls
  std::unique_ptr<Scratch> scratch_;
};

/// Makes every label 4-connected, on the surface if depth is given (no connection across a depth
/// jump of more than depth_jump_ratio times the nearer depth): pieces lighter than min_weight and
/// unlabelled valid pixels join the label they share the longest border with, or become -1. Labels
/// renumbered 0..n-1; returns n. valid: CV_8UC1 or empty (all valid); weight: CV_32FC1 (e.g. the
/// density) or empty (pixel count); depth: CV_32FC1 metres (0 = invalid) or empty. Not in the
/// thesis. Rules in full: docs/dasp_core.md#connectivity-enforcement
int enforceConnectivity(cv::Mat& labels, const cv::Mat& valid, const cv::Mat& weight,
                        double min_weight, const cv::Mat& depth = cv::Mat(),
                        float depth_jump_ratio = DaspConfig{}.depth_jump_ratio);

/// Superpoint fit: per label the mean colour, position and pixel position, plane-fit normal and
/// eigenvalue shape properties (§3.2.3). labels CV_32SC1 with values -1..n-1.
/// radius_m and depth_exponent give each superpixel's Superpixel::radius_m (radiusAtDepth).
std::vector<Superpixel> fitSuperpoints(const cv::Mat& labels, const PixelFeatures& features,
                                       const cv::Mat& density, float radius_m,
                                       float depth_exponent = 2.0f);

}  // namespace dasp

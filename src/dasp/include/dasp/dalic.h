// Density-Adaptive Local Iterative Clustering (DALIC, thesis alg. 3) with the metrics of ASP and
// DASP (d_DA, eq. 3.19-3.21).
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "dasp/dasp.h"
#include "dasp/features.h"
#include "dasp/pixel_allocator.h"
#include "dasp/sampling.h"

namespace dasp {

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
  float weight_depth = 0.0f;  ///< kDepthAdaptive only: DaspExperimental::weight_depth.
  float window_multiple = 1.5f;
  float radius_m = 0.02f;  ///< R for kDepthAdaptive / kColorDepth2D (metres).
  /// kDepthAdaptive: DaspExperimental::depth_exponent; a cluster at depth z has the radius
  /// radiusAtDepth(radius_m, z, depth_exponent) in d_DA and in its window.
  float depth_exponent = 2.0f;
  /// Purge clusters with fewer pixels than this fraction of their expected area 1/rho.
  float min_size_fraction = 0.1f;
  /// If > 0, after each update the number of clusters is brought to this value by splitting
  /// the clusters with the largest density mass or dropping the ones with the smallest.
  int target_count = 0;
  int threads = 1;  ///< 1 = single-threaded, 0 = all cores.
};

/// DALIC parameters of the RGB-D methods (DASP, streaming DASP, the naive ASP_RGBD baseline)
/// from one config: its weights, window, purge fraction and threads, with the given metric,
/// radius R (metres) and count-control target (0 = none).
DalicParams dalicParams(const DaspConfig& config, MetricKind metric, float radius_m,
                        int target_count);
/// DALIC parameters of ASP_RGB (metric kColor2D, count control to superpixel_count).
DalicParams dalicParams(const AspConfig& config);

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

  const DalicParams& params() const { return params_; }
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

}  // namespace dasp

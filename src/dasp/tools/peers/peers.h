// Peer superpixel methods run side by side with DASP in the tools: OpenCV ximgproc SLIC and
// SEEDS, and PCL supervoxels (VCCS). Linked into the tools only (dasp_peers), never into the dasp
// library. All return CV_32SC1 label images of the frame's size with labels 0..n-1 and -1 for
// pixels the method did not label.
#pragma once

#include <opencv2/core.hpp>

#include "dasp/dasp.h"

namespace dasp {
namespace peers {

/// OpenCV ximgproc SLIC on the CIELab image.
struct SlicConfig {
  int superpixel_count = 1000;  ///< K; region_size = round(sqrt(pixels / K)) pixels.
  int iterations = 10;          ///< OpenCV's default number of iterations.
  float ruler = 10.0f;          ///< Compactness (SLIC); ignored by SLICO.
  bool zero_parameter = false;  ///< true: SLICO (adaptive compactness) instead of SLIC.
  /// Minimum element size, in percent of the region size, below which enforceLabelConnectivity
  /// merges pieces (OpenCV default 25).
  int min_element_percent = 25;
};
cv::Mat computeOpenCvSlic(const cv::Mat& bgr, const SlicConfig& config);

/// OpenCV ximgproc SEEDS on the CIELab image.
struct SeedsConfig {
  int superpixel_count = 1000;  ///< K (SEEDS may return fewer: its block grid is coarse).
  int levels = 4;               ///< Block levels.
  int prior = 2;                ///< Shape smoothing prior (0..5).
  int histogram_bins = 5;       ///< Colour histogram bins per channel.
  int iterations = 4;           ///< Pixel-level iterations (OpenCV default).
};
cv::Mat computeOpenCvSeeds(const cv::Mat& bgr, const SeedsConfig& config);

/// PCL SupervoxelClustering (Papon et al. 2013) on the organized RGB-D point cloud.
struct VccsConfig {
  int superpixel_count = 1000;  ///< K; the seed resolution is chosen so that about K seeds fit.
  /// Seed resolution = seed_scale * sqrt(sum_u area(u) |n(u)|_1 / K): the 3D surface area of the
  /// valid pixels (dasp::computeFeatures) weighted by the number of seed-grid cells a surface of
  /// normal n cuts per unit area (|n_x| + |n_y| + |n_z|).
  /// 0.88 calibrated once over the 45 OSD learn frames at K = 1000, where scale 1 delivered 777
  /// supervoxels on average (0.88 = sqrt(0.777)).
  float seed_scale = 0.88f;
  float voxel_resolution_m = 0.008f;  ///< PCL's tutorial value; capped at seed resolution / 3.
  float color_importance = 0.2f;      ///< PCL tutorial defaults.
  float spatial_importance = 0.4f;
  float normal_importance = 1.0f;
  bool single_camera_transform = true;  ///< Depth-dependent voxel size for single-view clouds.
  /// VCCS's count follows the seed grid only roughly (from 0.7 K to 1.4 K on the OSD frames), so
  /// that methods are compared at the same number of superpixels the seed resolution is
  /// rescaled by sqrt(count / K) and VCCS rerun, at most count_matching_runs runs in all, until
  /// the count is within count_tolerance of K; the run closest to K is returned. 1 = no matching.
  int count_matching_runs = 6;
  float count_tolerance = 0.02f;
};
/// runs_used (optional): number of VCCS runs the count matching took.
cv::Mat computeVccs(const RgbdFrame& frame, const VccsConfig& config, int* runs_used = nullptr);

/// Renumbers labels >= 0 to 0..n-1 in order of first appearance; returns n.
int compactLabels(cv::Mat& labels);

}  // namespace peers
}  // namespace dasp

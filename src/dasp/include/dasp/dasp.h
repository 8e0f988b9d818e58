// Adaptive Superpixels (ASP, thesis ch. 2) and Depth-Adaptive Superpixels (DASP, thesis ch. 3).
// Entry points: computeDasp (RGB-D, metric d_DA), computeAspRgb (SLIC-like colour-only baseline)
// and computeAspRgbd (naive RGB-D baseline, ch. 3.3); the stages are in features.h, density.h,
// sampling.h, dalic.h, connectivity.h and superpoints.h. Pixel (u, v) = (column, row), pixel
// centres at integer coordinates (eq. 3.4); 3D in metres in the camera optical frame; labels
// CV_32SC1, -1 = unlabelled. Invalid input throws std::invalid_argument.
// Details: docs/dasp_core.md#conventions
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace dasp {

/// Pinhole intrinsics of the depth camera (registered colour image), in pixels.
struct Intrinsics {
  float fx = 525.0f;
  float fy = 525.0f;
  float cx = 319.5f;
  float cy = 239.5f;
};

/// One registered RGB-D frame.
struct RgbdFrame {
  cv::Mat color;  ///< CV_8UC3, BGR (OpenCV order), same size as depth.
  cv::Mat depth;  ///< CV_16UC1 millimetres (0 = invalid) or CV_32FC1 metres (0 or NaN = invalid).
  Intrinsics intrinsics;
};

/// How initial superpixel centres are drawn from the density (thesis §2.3, §2.5.1).
enum class SeedingMethod {
  kSpds,          ///< Simplified Poisson Disc Sampling, alg. 1 (coin flip per node of mass <= 1).
  kSpdsImproved,  ///< SPDS alg. 2 (random rounding of node mass <= 2^D, weighted child choice).
  kRandom,        ///< White noise: round(integral of density) i.i.d. draws from the density.
  kGrid,          ///< Regular square grid with spacing from the mean density (SLIC-style).
};

/// How the superpixel size is chosen for DASP (thesis §3.2.2).
enum class SizeMode {
  kCount,   ///< Scale the density so that it integrates to superpixel_count (eq. 3.17).
  kRadius,  ///< Fixed superpixel radius radius_m on the 3D surface (eq. 3.15).
};

/// Knobs of DASP kept for the ablations of docs/results/dasp.md; not thesis parameters, and the
/// defaults are the thesis' algorithm. Details: docs/dasp_core.md#experimental-knobs
struct DaspExperimental {
  /// Extra weight of the camera-z component in the compactness term (0: the thesis' isotropic
  /// d_DA, eq. 3.19). >= 0.
  float weight_depth = 0.0f;
  /// Exponent a of the depth in the density rho ~ D^a / n_z; 2 is eq. 3.15. One of 0, 0.5, 1,
  /// 1.5, 2; for a != 2 radius_m is the radius at 1 m.
  float depth_exponent = 2.0f;
  /// Clamp of the slant factor 1/|n_z| in the density (eq. 3.15/3.16). >= 1.
  float max_slant_factor = 5.0f;
};

/// Parameters of Depth-Adaptive Superpixels. Defaults are the thesis' values where it gives one.
struct DaspConfig {
  SizeMode size_mode = SizeMode::kCount;
  int superpixel_count = 1000;  ///< K in count mode (eq. 3.17); 1 <= K <= valid pixels.
  float radius_m = 0.02f;       ///< Superpixel radius R on the surface, metres (radius mode).
  int iterations = 5;           ///< DALIC iterations (alg. 3; thesis evaluation: 5).
  /// Weights of d_DA (eq. 3.19-3.21): mu_v of the 3D term |p - p_i|^2 / R^2, mu_c of the RGB
  /// term |c - c_i|^2 (colours in [0, 1]), mu_n of the normal term 1 - n . n_i.
  float weight_spatial = 1.0f;
  float weight_color = 2.0f;
  float weight_normal = 3.0f;
  /// DALIC search window half-size in units of the cluster's projected radius (C in alg. 3).
  float window_multiple = 1.5f;
  SeedingMethod seeding = SeedingMethod::kSpdsImproved;  ///< Seed sampling (§2.3, alg. 2).
  int normal_step_px = 2;  ///< Step h of the depth finite differences, pixels (eq. 3.6, 3.7).
  /// Make every superpixel 4-connected on the surface after the last iteration (not in the
  /// thesis): docs/dasp_core.md#connectivity-enforcement
  bool enforce_connectivity = true;
  /// Superpixels under this fraction of their expected pixel area are purged (unitless).
  float min_size_fraction = 0.1f;
  /// Relative depth jump |dD| / D (unitless) of a depth edge: no normal differences and no
  /// connectivity across it. Not in the thesis: docs/dasp_core.md#depth-jump-ratio
  float depth_jump_ratio = 0.02f;
  std::uint64_t seed = 0;  ///< Seed of the random generator (sampling). Same seed, same output.
  int threads = 1;         ///< Worker threads: 1 = single-threaded, 0 = all cores (TBB).
  DaspExperimental experimental;  ///< Ablation knobs; leave at their defaults.
};

/// Parameters of (colour-only) Adaptive Superpixels, the ASP_RGB baseline.
struct AspConfig {
  int superpixel_count = 1000;  ///< Wanted number of superpixels (constant density case).
  int iterations = 5;           ///< DALIC iterations.
  float weight_spatial = 1.0f;  ///< Weight of the compactness term (|u - u_i| / R_rho(u_i))^2.
  /// Weight of the RGB term |c - c_i|^2, colours in [0, 1]; 100 matches SLIC's compactness
  /// m = 10 (docs/dasp_core.md#asp-colour-weight).
  float weight_color = 100.0f;
  float window_multiple = 1.5f;  ///< DALIC search window half-size in units of R_rho.
  SeedingMethod seeding = SeedingMethod::kSpdsImproved;
  bool enforce_connectivity = true;
  float min_size_fraction = 0.1f;  ///< As DaspConfig::min_size_fraction.
  /// Optional user density (CV_32FC1, superpixels per pixel, >= 0, same size as the image).
  /// Empty: constant density. If given it is rescaled to integrate to superpixel_count.
  cv::Mat density;
  std::uint64_t seed = 0;
  int threads = 1;  ///< 1 = single-threaded, 0 = all cores.
};

/// One superpixel (superpoint) with its mean features and eigenvalue shape properties (§3.2.3).
struct Superpixel {
  int id = -1;               ///< Index in Superpixels::superpixels and value in the label image.
  float u = 0.0f, v = 0.0f;  ///< Mean pixel position (column, row) in pixels.
  int pixel_count = 0;       ///< Number of pixels with this label.
  Eigen::Vector3f color = Eigen::Vector3f::Zero();     ///< Mean colour, RGB order, in [0, 1].
  Eigen::Vector3f position = Eigen::Vector3f::Zero();  ///< Mean 3D point, metres, optical frame.
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();   ///< Plane-fit unit normal, towards camera.
  float radius_m = 0.0f;      ///< Nominal 3D radius R at this superpixel's depth (metres).
  float density = 0.0f;       ///< Density rho at the centre (superpixels per pixel).
  float thickness = 0.0f;     ///< 2d = 4 sqrt(w1), metres (w1 smallest covariance eigenvalue).
  float eccentricity = 0.0f;  ///< sqrt(1 - b^2 / a^2).
  float flatness = 0.0f;      ///< sqrt(1 - d^2 / a^2).
  float area_m2 = 0.0f;       ///< pi a b, square metres.
};

/// Result of a superpixel computation.
struct Superpixels {
  cv::Mat labels;  ///< CV_32SC1, index into superpixels, -1 = invalid depth or unassigned.
  std::vector<Superpixel> superpixels;
};

/// Depth-Adaptive Superpixels (alg. 4). Throws std::invalid_argument for bad input (sizes or
/// types that do not match, no valid depth, K out of range, intrinsics that are not finite and
/// positive, nonsensical parameters).
/// Each calling thread keeps one set of per-pixel working buffers (a DaspSegmenter, about 55
/// bytes a pixel: 17 MB at 640x480) until it exits, so that repeated calls do not allocate and
/// page them in again; use a DaspSegmenter of your own to control that memory.
Superpixels computeDasp(const RgbdFrame& frame, const DaspConfig& config = {});

/// DASP on a stream of frames: the same algorithm and result as computeDasp with this config,
/// but the per-pixel working buffers (features, density, DALIC labels and distances) are kept
/// from one frame to the next, so that a stream of same-sized frames allocates and clears no
/// per-pixel memory except the returned labels. Not thread-safe: one object per thread.
class DaspSegmenter {
 public:
  explicit DaspSegmenter(const DaspConfig& config = {});
  ~DaspSegmenter();
  DaspSegmenter(const DaspSegmenter&) = delete;
  DaspSegmenter& operator=(const DaspSegmenter&) = delete;

  /// Superpixels of one frame; throws std::invalid_argument like computeDasp.
  Superpixels compute(const RgbdFrame& frame);
  const DaspConfig& config() const { return config_; }
  /// Parameters for the following frames (checked by compute()).
  void setConfig(const DaspConfig& config) { config_ = config; }

 private:
  struct Buffers;
  DaspConfig config_;
  std::unique_ptr<Buffers> buffers_;
};

/// Colour-only Adaptive Superpixels (ASP_RGB): constant density (or config.density) and the
/// metric of def. 7 over RGB. 3D fields of the result are zero. Every pixel is labelled.
Superpixels computeAspRgb(const cv::Mat& color, const AspConfig& config = {});

/// Naive RGB-D Adaptive Superpixels (ASP_RGBD, ch. 3.3): constant density over the pixels with
/// valid depth and the direct-product metric
///   weight_color |c - c_i|^2 + weight_spatial ((|u - u_i| / R_px)^2 + ((z - z_i) / R)^2),
/// R_px the constant-density radius in pixels and R the mean 3D radius of count mode (no 3D
/// density adaptation, no normals). Uses the count, iterations, weights, window, seeding,
/// connectivity, seed and threads of the config. Same input checks as computeDasp.
Superpixels computeAspRgbd(const RgbdFrame& frame, const DaspConfig& config = {});

}  // namespace dasp

// Partition quality metrics for superpixels and segmentations (thesis appendix A and the
// superpixel benchmark literature), evaluated over a validity mask. labels: CV_32SC1, < 0 =
// unlabelled; ground_truth: CV_32SC1, CV_16UC1 or CV_8UC1; mask: CV_8UC1 (non-zero = evaluate) or
// empty (all pixels); 4-neighbourhoods. Segment-versus-reference metrics count all unlabelled
// pixels in the mask as ONE extra segment; shape metrics look at segments >= 0 only. Invalid
// input throws std::invalid_argument. Details: docs/dasp_core.md#metrics
#pragma once

#include <opencv2/core.hpp>

#include <cstddef>
#include <vector>

namespace dasp {
namespace metrics {

/// Boundary agreement between a partition and a reference partition.
/// A pixel is a boundary pixel of a partition if it is in the mask and one of its 4-neighbours is
/// in the mask and carries a different label (both sides of an edge are marked; the mask border
/// and the image border are not boundaries). A boundary pixel is matched if a boundary pixel of
/// the other partition lies within `tolerance_px` in the Chebyshev (square window) sense, as in
/// the superpixel benchmark of Stutz et al. and Neubert & Protzel.
struct BoundaryScores {
  /// Fraction of reference boundary pixels matched by a partition boundary pixel. This is the
  /// literature's boundary recall (normalised by the ground-truth boundary). 1 if the reference
  /// has no boundary inside the mask.
  double recall = 0.0;
  /// Fraction of partition boundary pixels matched by a reference boundary pixel. Thesis def. 13
  /// (eq. A.1) normalises by the partition boundary |dP| and therefore equals this number.
  /// 1 if the partition has no boundary inside the mask.
  double precision = 0.0;
  /// Harmonic mean of precision and recall (0 if both are 0).
  double f1 = 0.0;
  std::size_t reference_boundary_pixels = 0;
  std::size_t partition_boundary_pixels = 0;
};

/// Default boundary tolerance in pixels (2 px, the usual choice for 640x480 images).
constexpr int kDefaultBoundaryTolerancePx = 2;

/// Boundary pixels of `labels` inside `mask` as CV_8UC1 (255 = boundary), see BoundaryScores.
cv::Mat boundaryMap(const cv::Mat& labels, const cv::Mat& mask);

/// Boundary precision, recall and F1 of `labels` against `ground_truth`. Works for superpixels
/// (recall is the figure of interest) and for full segmentations (F1). tolerance_px >= 0.
BoundaryScores boundaryScores(const cv::Mat& labels, const cv::Mat& ground_truth,
                              const cv::Mat& mask, int tolerance_px = kDefaultBoundaryTolerancePx);

/// Undersegmentation error of thesis def. 14 (eq. A.3):
///   USE = (1/N) sum_T sum_{S : |S n T| / |S| > gamma} |S|  -  1,
/// N = number of pixels in the mask, S superpixels, T reference segments, all clipped to the mask.
/// 0 is best. gamma in [0, 1].
double undersegmentationErrorThesis(const cv::Mat& labels, const cv::Mat& ground_truth,
                                    const cv::Mat& mask, double gamma = 0.05);

/// Undersegmentation error in the form of Neubert & Protzel (2012):
///   UE = (1/N) sum_T sum_{S n T != 0} min(|S n T|, |S \ T|).
/// Counts for every superpixel straddling a reference boundary the smaller of its two parts. 0
/// best.
double undersegmentationErrorNp(const cv::Mat& labels, const cv::Mat& ground_truth,
                                const cv::Mat& mask);

/// Achievable segmentation accuracy: ASA = (1/N) sum_S max_T |S n T|, the accuracy of the best
/// segmentation that can be composed from the superpixels. 1 is best.
double achievableSegmentationAccuracy(const cv::Mat& labels, const cv::Mat& ground_truth,
                                      const cv::Mat& mask);

/// Connectivity of the segments (thesis def. 15-17), 4-connectivity inside the mask.
struct ConnectivityScores {
  /// CQ(P) = (1/N) sum_S |S| (1 - max_i |c_i| / |S|), eq. A.5; N = labelled pixels in the mask.
  /// 0 means every segment is connected.
  double quotient = 0.0;
  std::size_t segments = 0;               ///< segments (labels >= 0) with a pixel in the mask
  std::size_t disconnected_segments = 0;  ///< of those, how many have more than one component
};
ConnectivityScores connectivity(const cv::Mat& labels, const cv::Mat& mask);

/// Number of distinct labels >= 0 with at least one pixel inside the mask.
std::size_t countSegments(const cv::Mat& labels, const cv::Mat& mask);

/// Isoperimetric quotient of the partition (thesis def. 18-19, eq. A.6-A.7), the compactness "CO"
/// of Schick et al.: sum_S (|S| / N) * 4 pi |S| / |dS|^2, where |S| counts the segment's pixels in
/// the mask and |dS| those of its pixels that have a 4-neighbour outside the segment (other label,
/// outside the mask or outside the image). N = labelled pixels in the mask. On the pixel lattice a
/// digital disc reaches values somewhat above 1, a square about pi/4.
double isoperimetricQuotient(const cv::Mat& labels, const cv::Mat& mask);

/// 3D isoperimetric quotient (eq. A.13-A.15), area-weighted over segments like eq. A.7 with the 3D
/// area as weight:
///   Area3D(S) = (1/f^2) sum_{u in S} D(u)^2 / n_z(u),  Perimeter3D(S) = (1/f) sum_{u in dS}
///   D(u)/n_z(u)
/// `depth_m`: CV_32FC1 depth in metres; `normals`: CV_32FC3 unit normals in the camera frame
/// (z towards the camera or away; |n_z| is used). n_z is clamped to at least `min_normal_z` so that
/// surfaces seen at grazing angles do not dominate (0 < min_normal_z <= 1). Pixels with a
/// non-finite or non-positive depth or a non-finite normal are skipped. focal_px > 0.
double isoperimetricQuotient3d(const cv::Mat& labels, const cv::Mat& mask, const cv::Mat& depth_m,
                               const cv::Mat& normals, double focal_px, double min_normal_z = 0.1);

/// How segment means are formed for the compression metrics.
enum class FeatureMean {
  kArithmetic,  ///< plain mean (colour, depth, position)
  kUnitVector,  ///< mean re-normalised to unit length (normals, thesis §2.2 "non-linear group")
};

/// Compression error (def. 20, eq. A.8) and explained variation (def. 21, eq. A.9) of a feature.
struct CompressionScores {
  /// sqrt((1/N) sum_S sum_{x in S} ||f(x) - f_S||^2), in the feature's unit. 0 is best.
  double compression_error = 0.0;
  /// sum_S |S| ||f_S - f_mean||^2 / sum_x ||f(x) - f_mean||^2. 1 is best for arithmetic means;
  /// unit-vector means can exceed 1 (the thesis reports this for noisy normals).
  double explained_variation = 0.0;
  std::size_t pixels = 0;  ///< N: pixels in the mask with a finite feature value
};
/// `features`: CV_32FC1..CV_32FC4 (or CV_8UC3, taken as 0..255 values). Pixels whose feature has a
/// non-finite channel are skipped. Throws if no pixel is left.
CompressionScores compressionScores(const cv::Mat& labels, const cv::Mat& mask,
                                    const cv::Mat& features,
                                    FeatureMean mean = FeatureMean::kArithmetic);

/// Mean pixel position (x, y) of each segment (labels >= 0, mask only), in label order.
std::vector<cv::Point2d> segmentCentroids(const cv::Mat& labels, const cv::Mat& mask);

/// Uniform distribution error (thesis def. 22-23, eq. A.10-A.12).
struct UniformDistributionScores {
  /// sqrt(sum_v (rho_C(v) - rho_0)^2) over the mask pixels v, eq. A.12, where rho_C is the sum of
  /// Gaussian kernels (eq. A.11) at the segment centroids with sigma* chosen so that
  /// k(0) = rho_0 = |C| / |mask|. Grows with the image size.
  double error = 0.0;
  /// The same deviation as a root-mean-square relative to rho_0:
  /// sqrt(mean_v (rho_C(v) - rho_0)^2) / rho_0 (size independent).
  double relative_rms = 0.0;
  double sigma_px = 0.0;  ///< kernel standard deviation sigma* in pixels
};
UniformDistributionScores uniformDistributionError(const cv::Mat& labels, const cv::Mat& mask);

/// Total relative density error of eq. 2.15, E_rel = int |A_rho - rho| / int rho, with the
/// density approximation of eq. 2.5: every point u_i contributes a unit-mass Gaussian kernel
/// K(u | u_i, sigma_i) = rho(u_i) exp(-pi rho(u_i) ||u - u_i||^2), i.e. sigma_i = rho(u_i)^(-1/2)
/// in eq. 2.4 (the thesis prints rho^-D, which would not give unit mass). `density`: CV_32FC1 or
/// CV_64FC1, points per pixel, >= 0. `points`: pixel coordinates (x, y) inside the image. The
/// integrals run over the mask. 0 is a perfect representation.
double relativeDensityError(const cv::Mat& density, const std::vector<cv::Point2d>& points,
                            const cv::Mat& mask = cv::Mat());

/// Boundary matching counts of one segmentation (or one threshold) against a reference, the
/// numbers behind BoundaryScores; counts of several images add up (ODS).
struct BoundaryCounts {
  double threshold = 0.0;
  std::size_t partition_pixels = 0;  ///< |B(P)|
  std::size_t precise_pixels = 0;    ///< of those, matched by a reference boundary pixel
  std::size_t reference_pixels = 0;  ///< |B(X)|
  std::size_t recalled_pixels = 0;   ///< of those, matched by a partition boundary pixel
  double precision() const;          ///< 1 when there is no partition boundary (as above)
  double recall() const;             ///< 1 when there is no reference boundary
  double f1() const;
  BoundaryCounts& operator+=(const BoundaryCounts& other);
};

/// Boundary counts of the segmentations (ucm >= t) for every t of `thresholds`, in one pass over
/// the pixels: precision and recall equal boundaryScores(segmentation at t,
/// ground_truth, mask, tolerance_px). ucm from ultrametricContourMap (dasp/segmentation.h)
/// with the same mask.
std::vector<BoundaryCounts> boundaryCurve(const cv::Mat& ucm, const cv::Mat& ground_truth,
                                          const cv::Mat& mask, const std::vector<float>& thresholds,
                                          int tolerance_px = kDefaultBoundaryTolerancePx);

}  // namespace metrics
}  // namespace dasp

// Delta Density Sampling (thesis §5.2.2, alg. 5): re-sample a point set for a new density by
// removing and adding only as many points as the change of density asks for, so that points
// stay where the density did not change (the seeds of temporal-stable superpixels).
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "dasp/dasp.h"
#include "dasp/sampling.h"

namespace dasp {

/// Parameters of Delta Density Sampling.
struct DeltaDensityConfig {
  /// Sampler of rho_+ and rho_- (the thesis uses SPDS). kGrid is not allowed: it would place
  /// points for any positive density and ignores the delta density's mass.
  SeedingMethod sampling = SeedingMethod::kSpdsImproved;
  /// The point kernels of eq. 2.5 are cut off at this many standard deviations.
  float kernel_cutoff_sigma = 3.0f;
  /// Gaussian smoothing of the delta density, in multiples of the mean superpixel radius
  /// R_rho = 1 / sqrt(pi mean rho): cancels the superpixel-sized ripples of Delta rho. 0 = the
  /// literal alg. 5. Not in the thesis: docs/dasp_core.md#delta-density-smoothing
  float smoothing_radius_multiple = 2.0f;
};

/// Realised density of a point set (eq. 2.5) for the target `density`: every point contributes
/// one unit of mass as the kernel rho(u_i) exp(-pi rho(u_i) |u - u_i|^2) with rho(u_i) the
/// target density at the point, restricted to (and renormalised over) the pixels where the
/// target density is positive, so that the integral equals the number of points on such pixels.
/// Points on pixels of zero density contribute nothing. CV_32FC1.
cv::Mat realizedDensity(const cv::Mat& density, const std::vector<Seed>& points,
                        float kernel_cutoff_sigma = 3.0f);

/// Nearest-neighbour index over a fixed point set with removal (the "argmin, then remove" of
/// alg. 5): a uniform grid of buckets, searched ring by ring, so that M removals among N points
/// cost about O(M + N) instead of O(N M).
class NearestPointIndex {
 public:
  /// cell_size_px > 0: bucket edge length (about the mean point spacing works best).
  NearestPointIndex(const std::vector<Seed>& points, int width, int height, float cell_size_px);
  /// Index of the nearest point not yet removed and marks it removed; -1 if none is left.
  int removeNearest(float u, float v);
  int remaining() const { return remaining_; }

 private:
  int cellOf(float coordinate, int cells) const;
  const std::vector<Seed>& points_;
  float cell_size_;
  int cols_ = 1, rows_ = 1;
  std::vector<std::vector<int>> buckets_;  ///< point indices per cell (removed ones erased)
  int remaining_ = 0;
};

/// Result of one Delta Density Sampling step.
struct DeltaDensityResult {
  std::vector<Seed> points;  ///< Kept points (in input order) followed by the added points.
  /// Per output point: index of the input point it continues, or -1 for an added point.
  std::vector<int> origin;
  int removed_by_density = 0;  ///< points removed at the samples of rho_-
  int removed_invalid = 0;     ///< points removed because their pixel has zero density
  int added = 0;               ///< points sampled from rho_+
  double positive_mass = 0.0;  ///< integral of rho_+ (expected additions)
  double negative_mass = 0.0;  ///< integral of rho_- (expected removals)
};

/// Delta Density Sampling (alg. 5) of `density` (CV_32FC1, >= 0, points per pixel) from the
/// points of the previous step: Delta rho = rho - A_rho(. | points) (realizedDensity), smoothed
/// (config), split into rho_+ and rho_- (eq. 5.5, 5.6); for every sample of rho_- the nearest
/// remaining point is removed, and the samples of rho_+ are added. In expectation the output
/// has integral(rho) points. Throws std::invalid_argument for a bad density or config.
DeltaDensityResult deltaDensitySampling(const cv::Mat& density, const std::vector<Seed>& points,
                                        const DeltaDensityConfig& config, std::uint64_t seed);

}  // namespace dasp

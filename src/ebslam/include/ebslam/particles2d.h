#pragma once

// Particle set over SE(2) shared by EB-PF (6.4-6.5) and EB-SLAM-2D (7.3), laid out for speed:
// structure of arrays, rotation kept as a unit vector (cos, sin) advanced by small-angle steps,
// scores with a global decay scale (DecayingScores), a table-based normal generator.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "ebslam/exponential_decay.h"

namespace ebslam {

/// Planar pose of the camera frame in the map frame: position [m], heading [rad] (eq. 6.31).
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
};

/// Dense float grid on the ceiling plane. Cell (row r, column c) covers world x in
/// [origin_x + c res, origin_x + (c+1) res) and y in [origin_y + r res, origin_y + (r+1) res).
/// `data` holds the width * height cells row by row plus one trailing 0, the value returned for
/// points outside the grid (lets the particle loop look up without branches).
struct GridMap2f {
  int width = 0;
  int height = 0;
  double resolution_m = 0.0;
  double origin_x_m = 0.0;
  double origin_y_m = 0.0;
  std::vector<float> data;

  GridMap2f() = default;
  /// Throws std::invalid_argument for non-positive sizes or resolution.
  GridMap2f(int width, int height, double resolution_m, double origin_x_m, double origin_y_m,
            float value = 0.0f);

  float& at(int col, int row) { return data[static_cast<std::size_t>(row) * width + col]; }
  float at(int col, int row) const { return data[static_cast<std::size_t>(row) * width + col]; }
  /// Value of the cell containing world point (x, y); 0 outside the grid.
  float lookup(double x, double y) const {
    const double fc = (x - origin_x_m) * inv_resolution_;
    const double fr = (y - origin_y_m) * inv_resolution_;
    if (!(fc >= 0.0 && fr >= 0.0 && fc < width && fr < height)) return 0.0f;  // outside
    return data[static_cast<std::size_t>(fr) * width + static_cast<std::size_t>(fc)];
  }
  double invResolution() const { return inv_resolution_; }
  std::size_t cellCount() const { return static_cast<std::size_t>(width) * height; }

 private:
  double inv_resolution_ = 0.0;
};

/// Fast standard-normal samples: xoshiro256++ picks entries of a table of 2^10 normal quantiles
/// Phi^-1((i + 0.5) / 2^10), so each sample is one load from a 4 KB table that stays in L1
/// cache (range +-3.3 sigma; variance 0.9987). One 64-bit draw gives six samples (the diffusion
/// of two particles). Deterministic for a seed.
class FastNormalGenerator {
 public:
  explicit FastNormalGenerator(std::uint64_t seed);
  /// xoshiro256++ (Blackman & Vigna); inline: it runs once per particle and batch.
  std::uint64_t nextU64() {
    const std::uint64_t result = rotl(state_[0] + state_[3], 23) + state_[0];
    const std::uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = rotl(state_[3], 45);
    return result;
  }
  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(nextU64() >> 11) * 0x1.0p-53; }
  /// Four independent standard normals from one 64-bit draw (10 of every 16 bits).
  void normals4(float out[4]) {
    const std::uint64_t r = nextU64();
    constexpr std::uint64_t mask = (std::uint64_t{1} << kTableBits) - 1;
    out[0] = table_[r & mask];
    out[1] = table_[(r >> 16) & mask];
    out[2] = table_[(r >> 32) & mask];
    out[3] = table_[(r >> 48) & mask];
  }
  /// Six independent standard normals from one 64-bit draw (10 bits each).
  void normals6(float out[6]) {
    const std::uint64_t r = nextU64();
    constexpr std::uint64_t mask = (std::uint64_t{1} << kTableBits) - 1;
    for (int k = 0; k < 6; ++k) out[k] = table_[(r >> (10 * k)) & mask];
  }
  static constexpr int kTableBits = 10;

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::array<std::uint64_t, 4> state_{};
  const float* table_ = nullptr;
};

/// N weighted pose hypotheses.
class ParticleSet2D {
 public:
  ParticleSet2D() = default;

  /// All particles at `start` plus Gaussian noise of the given standard deviations [m, rad];
  /// scores set to `initial_score` (eq. 6.29: 1). Throws std::invalid_argument if n < 1.
  void reset(int n, const Pose2& start, double spread_xy_m, double spread_theta_rad,
             double initial_score, std::uint64_t seed);

  int size() const { return static_cast<int>(x_.size()); }

  /// One (batched) EB-PF step: every particle diffuses with N(0, diag(sigma_xy^2, sigma_xy^2,
  /// sigma_theta^2)) (eq. 6.38/6.39, sigmas already scaled for the batch), then its score is
  /// updated with the map values at the batch's events mapped through its pose (eq. 6.29/6.30).
  /// pixel_index[j] indexes offset_x / offset_y (camera-frame ceiling offsets [m]).
  void step(const std::uint32_t* pixel_index, int batch, const float* offset_x,
            const float* offset_y, const GridMap2f& map, double sigma_xy, double sigma_theta,
            const BatchDecay& decay);

  /// Systematic (low-variance) resampling: one uniform u0 in [0, 1/N), particle k copied for
  /// each u0 + j/N in its cumulative-weight interval. Exact (every particle is drawn
  /// floor/ceil(N w_k) times), O(N). Children keep their parent's score unless reset_scores,
  /// in which case all scores become the mean score. Returns false (and does nothing) when the
  /// total score is zero or not finite.
  bool resampleSystematic(bool reset_scores);

  /// Score-weighted mean pose (heading as the angle of the weighted mean direction); the plain
  /// mean when all scores are zero.
  Pose2 weightedMean() const;
  /// weightedMean with the heading as a unit vector (cos, sin), without trigonometry; (1, 0)
  /// if the mean direction vanishes.
  void weightedMean(double& x, double& y, double& cos_theta, double& sin_theta) const;
  /// Particle with the highest score.
  Pose2 best() const;
  Pose2 particle(int i) const;
  /// Score of particle i normalised so that the scores sum to 1 (0 if all are zero).
  double normalisedWeight(int i) const;
  double score(int i) const { return scores_.score(static_cast<std::size_t>(i)); }

 private:
  // Pose state in float: 1 um resolution at 8 m is far below a sensor pixel (3 cm); the heading
  // unit vector is renormalised at every resampling.
  std::vector<float> x_, y_, cos_, sin_;
  DecayingScores scores_;
  FastNormalGenerator rng_{1};
  std::vector<float> scratch_x_, scratch_y_, scratch_c_, scratch_s_;
  std::vector<double> scratch_w_;
  std::vector<std::uint32_t> cell_;  // per particle: map cell of the current event
  std::vector<float> sum_;           // per particle: summed map values of the current batch
  std::vector<float> noise_x_, noise_y_, noise_theta_;  // per particle: this step's normals
};

}  // namespace ebslam

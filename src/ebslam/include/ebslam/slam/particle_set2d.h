#pragma once

// Particle set over SE(2) shared by EB-PF (6.4-6.5) and EB-SLAM-2D (7.3), laid out for speed:
// structure of arrays, rotation kept as a unit vector (cos, sin) advanced by small-angle steps,
// scores with a global decay scale (DecayingScores), a table-based normal generator.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "ebslam/events/pose.h"
#include "ebslam/slam/exponential_decay.h"
#include "ebslam/slam/fast_normal_generator.h"
#include "ebslam/slam/grid_map2f.h"

namespace ebslam {

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
  /// The same with `count` children instead of N (the particle count becomes `count`; KLD
  /// sampling). Throws std::invalid_argument if count < 1.
  bool resampleSystematic(bool reset_scores, int count);

  /// Replaces the particles by `poses`, all with score `score` (> 0); the noise generator keeps
  /// its state. Throws std::invalid_argument for an empty list.
  void assign(const std::vector<Pose2>& poses, double score);
  /// Appends `poses` with score `score` (mean-score scale of the current set).
  void append(const std::vector<Pose2>& poses, double score);
  /// Mean score of the particles (0 for an empty set).
  double meanScore() const;

  /// Odometry motion of every particle (sample_motion_model_odometry, Probabilistic Robotics
  /// 5.4, AMCL's "diff" model): the motion `delta` given in the particle's own frame (forward
  /// x, left y, turn theta) is split into rot1, trans, rot2, each disturbed by a zero-mean normal
  /// of standard deviation sqrt(a1 rot1^2 + a2 trans^2) (rotations) and sqrt(a3 trans^2 +
  /// a4 (rot1^2 + rot2^2)) (translation), then applied. A motion shorter than 1 mm turns in place
  /// (rot1 = 0).
  void applyOdometry(const Pose2& delta, double alpha1, double alpha2, double alpha3,
                     double alpha4);

  /// Mean over the particles of the mean map value per event of the last step() (how well the
  /// set explains the last batch; 0 before the first step).
  double lastBatchMeanValue() const;

  /// Score-weighted covariance of (x [m], y [m], theta [rad]) around the weighted mean (heading
  /// differences wrapped to (-pi, pi]).
  Eigen::Matrix3d covariance() const;

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
  void resizeWorkspace(std::size_t count);

  std::vector<float> x_, y_, cos_, sin_;
  DecayingScores scores_;
  FastNormalGenerator rng_{1};
  std::vector<float> scratch_x_, scratch_y_, scratch_c_, scratch_s_;
  std::vector<double> scratch_w_;
  std::vector<std::uint32_t> cell_;  // per particle: map cell of the current event
  std::vector<float> sum_;           // per particle: summed map values of the current batch
  std::vector<float> noise_x_, noise_y_, noise_theta_;  // per particle: this step's normals
  int last_batch_ = 0;                                  // events of the last step()
};

}  // namespace ebslam

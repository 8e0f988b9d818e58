#pragma once

// Information integration of event streams by exponential decay (thesis 6.3, eq. 6.13-6.30).

#include <cstddef>
#include <vector>

namespace ebslam {

/// Decay constant alpha from the relative influence beta of the last G0 events (eq. 6.27):
/// alpha = 1 - (1 - beta)^(1/G0). Throws std::invalid_argument unless 0 < beta < 1 and g0 > 0.
double decayFromInfluence(double beta, double g0);

/// Factors of the batched score update (eq. 6.30): processing B events at once as
/// s = keep * s + gain * sum_{j<B} r_j with keep = (1-alpha)^B and gain = (1 - keep) / B.
struct BatchDecay {
  double keep = 1.0;
  double gain = 0.0;
};
/// Throws std::invalid_argument unless 0 < alpha <= 1 and batch_size >= 1.
BatchDecay batchDecay(double alpha, int batch_size);

/// Weighted mean of eq. 6.14 with exponential weights w(dt) = exp(-lambda dt) (eq. 6.17),
/// evaluated directly from all samples (O(n)); the reference for the recursion below.
/// times_s must be non-decreasing [s]; lambda [1/s] >= 0. Throws std::invalid_argument on
/// mismatched sizes, empty input, decreasing times or a negative lambda.
double exponentialDecayClosedForm(const std::vector<double>& times_s,
                                  const std::vector<double>& values, double lambda_per_s);

/// The recursion of proposition 3 (eq. 6.19-6.20): s_n = (1 - alpha_n) s_{n-1} + alpha_n r_n with
/// alpha_n = alpha_{n-1} / (alpha_{n-1} + exp(-lambda (t_n - t_{n-1}))), alpha_1 = 1.
/// O(1) memory and time per sample.
class ExponentialDecayIntegrator {
 public:
  /// lambda_per_s: decay constant [1/s], >= 0 (0 = plain running mean, case 1 of 6.3.1).
  explicit ExponentialDecayIntegrator(double lambda_per_s);

  /// Adds sample r observed at time t_s [s]; returns the new total score s_n.
  /// Throws std::invalid_argument if t_s is earlier than the previous sample.
  double add(double t_s, double r);

  double score() const { return score_; }
  /// alpha_n of the last sample (1 after the first sample, undefined (0) before).
  double alpha() const { return alpha_; }
  std::size_t count() const { return count_; }

 private:
  double lambda_;
  double score_ = 0.0;
  double alpha_ = 0.0;
  double last_t_ = 0.0;
  std::size_t count_ = 0;
};

/// Scores of many hypotheses (particles) updated with the constant-alpha decay of eq. 6.29/6.30.
///
/// The decay (1-alpha)^B is common to all scores, so it is applied once to a global scale factor
/// g instead of to every score: the stored value r_i represents s_i = g * r_i, and an update
/// s_i <- keep * s_i + gain * sum_i becomes g <- keep * g, r_i <- r_i + (gain / g) * sum_i.
/// When g becomes small the stored values are renormalised (r_i <- g r_i, g <- 1), which keeps
/// the representation exact up to floating-point rounding.
class DecayingScores {
 public:
  DecayingScores() = default;
  /// n scores, all with the value `initial` (eq. 6.29 starts with s_i = 1).
  DecayingScores(std::size_t n, double initial);

  std::size_t size() const { return stored_.size(); }
  void assign(std::size_t n, double initial);

  /// Starts one batch update: applies `keep` to the global scale and returns the factor by which
  /// a particle's summed partial scores are multiplied before being added to its stored value.
  double beginUpdate(const BatchDecay& decay);
  /// Adds factor * partial_sum to hypothesis i (factor from beginUpdate).
  void addStored(std::size_t i, double factor_times_sum) { stored_[i] += factor_times_sum; }

  /// Actual score s_i.
  double score(std::size_t i) const { return scale_ * stored_[i]; }
  /// Stored values (s_i / scale); proportional to the scores, enough for resampling and means.
  const std::vector<double>& stored() const { return stored_; }
  std::vector<double>& stored() { return stored_; }
  double scale() const { return scale_; }
  /// Folds the scale into the stored values (scale becomes 1).
  void renormalise();

 private:
  std::vector<double> stored_;
  double scale_ = 1.0;
};

}  // namespace ebslam

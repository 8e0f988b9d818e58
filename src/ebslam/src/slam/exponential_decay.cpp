#include "ebslam/slam/exponential_decay.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace ebslam {

double decayFromInfluence(double beta, double g0) {
  if (!(beta > 0.0 && beta < 1.0)) {
    throw std::invalid_argument("decayFromInfluence: beta must lie in (0, 1), got " +
                                std::to_string(beta));
  }
  if (!(g0 > 0.0) || !std::isfinite(g0)) {
    throw std::invalid_argument("decayFromInfluence: G0 must be positive, got " +
                                std::to_string(g0));
  }
  return 1.0 - std::pow(1.0 - beta, 1.0 / g0);
}

BatchDecay batchDecay(double alpha, int batch_size) {
  if (!(alpha > 0.0 && alpha <= 1.0)) {
    throw std::invalid_argument("batchDecay: alpha must lie in (0, 1], got " +
                                std::to_string(alpha));
  }
  if (batch_size < 1) {
    throw std::invalid_argument("batchDecay: batch size must be >= 1, got " +
                                std::to_string(batch_size));
  }
  BatchDecay d;
  d.keep = std::pow(1.0 - alpha, batch_size);
  d.gain = (1.0 - d.keep) / batch_size;
  return d;
}

double exponentialDecayClosedForm(const std::vector<double>& times_s,
                                  const std::vector<double>& values, double lambda_per_s) {
  if (times_s.size() != values.size()) {
    throw std::invalid_argument("exponentialDecayClosedForm: times and values differ in size");
  }
  if (times_s.empty()) {
    throw std::invalid_argument("exponentialDecayClosedForm: no samples");
  }
  if (!(lambda_per_s >= 0.0)) {
    throw std::invalid_argument("exponentialDecayClosedForm: lambda must be >= 0");
  }
  const double t_n = times_s.back();
  double numerator = 0.0;
  double denominator = 0.0;
  for (std::size_t i = 0; i < times_s.size(); ++i) {
    if (i > 0 && times_s[i] < times_s[i - 1]) {
      throw std::invalid_argument("exponentialDecayClosedForm: times must be non-decreasing");
    }
    const double w = std::exp(-lambda_per_s * (t_n - times_s[i]));
    numerator += w * values[i];
    denominator += w;
  }
  return numerator / denominator;
}

ExponentialDecayIntegrator::ExponentialDecayIntegrator(double lambda_per_s)
    : lambda_(lambda_per_s) {
  if (!(lambda_per_s >= 0.0) || !std::isfinite(lambda_per_s)) {
    throw std::invalid_argument("ExponentialDecayIntegrator: lambda must be finite and >= 0");
  }
}

double ExponentialDecayIntegrator::add(double t_s, double r) {
  if (count_ == 0) {
    alpha_ = 1.0;  // alpha_1 = 1 (eq. 6.20)
  } else {
    if (t_s < last_t_) {
      throw std::invalid_argument("ExponentialDecayIntegrator: time runs backwards (" +
                                  std::to_string(t_s) + " s after " + std::to_string(last_t_) +
                                  " s)");
    }
    alpha_ = alpha_ / (alpha_ + std::exp(-lambda_ * (t_s - last_t_)));  // eq. 6.20
  }
  score_ = (1.0 - alpha_) * score_ + alpha_ * r;  // eq. 6.19
  last_t_ = t_s;
  ++count_;
  return score_;
}

DecayingScores::DecayingScores(std::size_t n, double initial) { assign(n, initial); }

void DecayingScores::assign(std::size_t n, double initial) {
  stored_.assign(n, initial);
  scale_ = 1.0;
}

double DecayingScores::beginUpdate(const BatchDecay& decay) {
  // Renormalise well before the scale underflows; 1e-100 leaves ample double range.
  if (scale_ < 1e-100) renormalise();
  scale_ *= decay.keep;
  return decay.gain / scale_;
}

void DecayingScores::renormalise() {
  for (double& v : stored_) v *= scale_;
  scale_ = 1.0;
}

}  // namespace ebslam

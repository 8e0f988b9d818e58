#include "ebslam/slam/exponential_decay.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace ebslam {
namespace {

// Proposition 3: the recursion of eq. 6.19/6.20 equals the weighted mean of eq. 6.14 with
// exponential weights, for irregular event times.
TEST(ExponentialDecay, RecursionEqualsClosedFormForIrregularTimes) {
  std::mt19937_64 rng(7);
  std::exponential_distribution<double> gap(2000.0);  // mean 0.5 ms between events
  std::uniform_real_distribution<double> value(-1.0, 3.0);
  for (const double lambda : {0.0, 10.0, 500.0, 5000.0}) {
    ExponentialDecayIntegrator integrator(lambda);
    std::vector<double> times;
    std::vector<double> values;
    double t = 1.0;
    for (int n = 0; n < 400; ++n) {
      t += (n % 7 == 3) ? 0.0 : gap(rng);  // include simultaneous events
      times.push_back(t);
      values.push_back(value(rng));
      const double recursive = integrator.add(t, values.back());
      const double closed = exponentialDecayClosedForm(times, values, lambda);
      ASSERT_NEAR(recursive, closed, 1e-9 * (1.0 + std::abs(closed)))
          << "lambda " << lambda << " n " << n;
      // alpha_n = 1 / A_n with A_n = sum_j exp(-lambda (t_n - t_j)) (proof of prop. 3).
      double a_n = 0.0;
      for (double tj : times) a_n += std::exp(-lambda * (t - tj));
      ASSERT_NEAR(integrator.alpha(), 1.0 / a_n, 1e-12);
    }
  }
}

// Special cases of 6.3.1: simultaneous events give the running mean (alpha_n = 1/n), a constant
// event interval mu = exp(-lambda c) gives alpha_n = (1 - mu) / (1 - mu^n).
TEST(ExponentialDecay, SpecialCasesOfSection631) {
  ExponentialDecayIntegrator same_time(100.0);
  double sum = 0.0;
  for (int n = 1; n <= 50; ++n) {
    sum += n;
    same_time.add(2.0, n);
    EXPECT_NEAR(same_time.alpha(), 1.0 / n, 1e-14);
    EXPECT_NEAR(same_time.score(), sum / n, 1e-12);
  }
  const double lambda = 3.0;
  const double c = 0.1;
  const double mu = std::exp(-lambda * c);
  ExponentialDecayIntegrator regular(lambda);
  for (int n = 1; n <= 200; ++n) {
    regular.add(n * c, 1.0);
    EXPECT_NEAR(regular.alpha(), (1.0 - mu) / (1.0 - std::pow(mu, n)), 1e-12);
  }
  EXPECT_NEAR(regular.alpha(), 1.0 - mu, 1e-12);  // eq. 6.26
}

TEST(ExponentialDecay, DecayFromInfluenceMatchesThesisExample) {
  // 6.3.2: beta = 0.95, G0 = 250 gives alpha ~ 0.012; the last G0 events carry weight beta.
  const double alpha = decayFromInfluence(0.95, 250.0);
  EXPECT_NEAR(alpha, 0.012, 0.0005);
  EXPECT_NEAR(1.0 - std::pow(1.0 - alpha, 250.0), 0.95, 1e-12);
  EXPECT_THROW(decayFromInfluence(1.0, 250.0), std::invalid_argument);
  EXPECT_THROW(decayFromInfluence(0.5, 0.0), std::invalid_argument);
  EXPECT_THROW(batchDecay(0.0, 3), std::invalid_argument);
  EXPECT_THROW(batchDecay(0.1, 0), std::invalid_argument);
}

// eq. 6.30 equals B single-event updates of eq. 6.29 when the B partial scores are equal, and
// the scaled representation equals the direct update.
TEST(ExponentialDecay, BatchAndScaledScoresEqualDirectUpdates) {
  const double alpha = decayFromInfluence(0.95, 40.0);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> value(0.0, 1.0);
  for (int b : {1, 3, 5}) {
    const BatchDecay decay = batchDecay(alpha, b);
    DecayingScores scaled(4, 1.0);
    std::vector<double> direct(4, 1.0);
    std::vector<double> batched(4, 1.0);
    for (int step = 0; step < 3000; ++step) {
      const double factor = scaled.beginUpdate(decay);
      for (std::size_t i = 0; i < 4; ++i) {
        const double r = value(rng);
        for (int j = 0; j < b; ++j) direct[i] = (1.0 - alpha) * direct[i] + alpha * r;
        batched[i] = decay.keep * batched[i] + decay.gain * (b * r);
        scaled.addStored(i, factor * (b * r));
      }
      for (std::size_t i = 0; i < 4; ++i) {
        ASSERT_NEAR(batched[i], direct[i], 1e-12);
        ASSERT_NEAR(scaled.score(i), direct[i], 1e-9);
      }
    }
  }
}

TEST(ExponentialDecay, RejectsBadInput) {
  EXPECT_THROW(ExponentialDecayIntegrator(-1.0), std::invalid_argument);
  ExponentialDecayIntegrator integrator(1.0);
  integrator.add(1.0, 0.5);
  EXPECT_THROW(integrator.add(0.5, 0.5), std::invalid_argument);
  EXPECT_THROW(exponentialDecayClosedForm({}, {}, 1.0), std::invalid_argument);
  EXPECT_THROW(exponentialDecayClosedForm({1.0, 0.0}, {1.0, 1.0}, 1.0), std::invalid_argument);
  EXPECT_THROW(exponentialDecayClosedForm({1.0}, {1.0, 1.0}, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace ebslam

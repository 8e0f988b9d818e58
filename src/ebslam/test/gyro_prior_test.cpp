// Gyro integrator (gyro_prior.h): exact integration of known rates, coverage rules, rejected
// samples, the bias estimate's convergence, and the IMU-to-sensor rotation fit and calibration.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "ebslam/simulation/handheld_motions.h"
#include "ebslam/simulation/imu_simulator.h"
#include "ebslam/slam/gyro_prior.h"

namespace ebslam {
namespace {

Eigen::Quaterniond expRotation(const Eigen::Vector3d& v) {
  const double a = v.norm();
  return a < 1e-15 ? Eigen::Quaterniond::Identity()
                   : Eigen::Quaterniond(Eigen::AngleAxisd(a, v / a));
}

const Eigen::Quaterniond kSensorFromImu =
    Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()));

TEST(GyroPrior, ConstantRateIntegratesExactlyInTheSensorFrame) {
  GyroPriorConfig config;
  config.sensor_from_imu = kSensorFromImu;
  GyroPrior gyro(config);
  const Eigen::Vector3d rate_imu(0.3, -0.2, 0.5);
  for (int k = 0; k <= 400; ++k) {  // 200 Hz for 2 s, starting at 1 s
    ASSERT_EQ(gyro.add(1000000 + 5000 * k, rate_imu), GyroPrior::AddResult::kAccepted);
  }
  // Across sample boundaries and inside one interval.
  for (const auto& [t0, t1] : std::vector<std::pair<std::int64_t, std::int64_t>>{
           {1000000, 3000000}, {1234567, 1876543}, {2000100, 2000200}, {1500000, 1500000}}) {
    const auto delta = gyro.deltaRotation(t0, t1);
    ASSERT_TRUE(delta.has_value());
    const Eigen::Quaterniond expected = expRotation(kSensorFromImu * rate_imu * 1e-6 * (t1 - t0));
    EXPECT_LT(delta->angularDistance(expected), 1e-9) << t0 << " " << t1;
  }
  // Holding the last rate for up to max_extrapolation_s (0.02 s), nothing beyond.
  const auto held = gyro.deltaRotation(2900000, 3015000);
  ASSERT_TRUE(held.has_value());
  EXPECT_LT(held->angularDistance(expRotation(kSensorFromImu * rate_imu * 0.115)), 1e-9);
  EXPECT_FALSE(gyro.deltaRotation(2900000, 3030000).has_value());
  EXPECT_FALSE(gyro.deltaRotation(999999, 1100000).has_value());  // before the first sample
  EXPECT_THROW(gyro.deltaRotation(2000000, 1000000), std::invalid_argument);
}

TEST(GyroPrior, GapsAndBadSamples) {
  GyroPrior gyro;
  EXPECT_EQ(gyro.add(0, Eigen::Vector3d(0.1, 0.0, 0.0)), GyroPrior::AddResult::kAccepted);
  EXPECT_EQ(gyro.add(5000, Eigen::Vector3d(0.1, 0.0, 0.0)), GyroPrior::AddResult::kAccepted);
  EXPECT_EQ(gyro.add(5000, Eigen::Vector3d(0.1, 0.0, 0.0)), GyroPrior::AddResult::kOutOfOrder);
  EXPECT_EQ(gyro.add(4000, Eigen::Vector3d(0.1, 0.0, 0.0)), GyroPrior::AddResult::kOutOfOrder);
  EXPECT_EQ(gyro.add(6000, Eigen::Vector3d(NAN, 0.0, 0.0)), GyroPrior::AddResult::kNonFinite);
  EXPECT_EQ(gyro.add(6000, Eigen::Vector3d(0.0, 40.0, 0.0)), GyroPrior::AddResult::kSaturated);
  EXPECT_EQ(gyro.sampleCount(), 2u);
  // A 0.1 s gap (max_sample_gap_s 0.05): nothing across it, fine on either side.
  EXPECT_EQ(gyro.add(105000, Eigen::Vector3d(0.1, 0.0, 0.0)), GyroPrior::AddResult::kAccepted);
  EXPECT_EQ(gyro.add(110000, Eigen::Vector3d(0.1, 0.0, 0.0)), GyroPrior::AddResult::kAccepted);
  EXPECT_TRUE(gyro.deltaRotation(0, 5000).has_value());
  EXPECT_FALSE(gyro.deltaRotation(4000, 6000).has_value());
  EXPECT_TRUE(gyro.deltaRotation(105000, 110000).has_value());
  // Discarding keeps the sample that starts the interval covering t.
  gyro.discardBefore(107000);
  EXPECT_TRUE(gyro.deltaRotation(107000, 110000).has_value());
  EXPECT_FALSE(gyro.deltaRotation(100000, 110000).has_value());
  GyroPriorConfig bad;
  bad.noise_density = -1.0;
  EXPECT_THROW(GyroPrior{bad}, std::invalid_argument);
  bad = {};
  bad.sensor_from_imu.coeffs() *= 2.0;
  EXPECT_THROW(GyroPrior{bad}, std::invalid_argument);
}

// A rotating gyro with a constant bias and white noise; the independent estimate is the true
// rotation plus jitter. The bias estimate converges; the bias correction then makes the gyro's
// rotation match the truth.
TEST(GyroPrior, BiasEstimateConverges) {
  GyroPriorConfig config;
  config.sensor_from_imu = kSensorFromImu;
  config.bias_random_walk = 0.0;
  GyroPrior gyro(config);
  const Eigen::Vector3d bias(0.02, -0.015, 0.01);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double noise = config.noise_density * std::sqrt(200.0);
  const auto true_rate = [](double t) {  // rad/s, IMU frame: turning about changing axes
    return Eigen::Vector3d(0.8 * std::sin(1.3 * t), 0.6 * std::cos(0.7 * t),
                           0.5 * std::sin(2.1 * t));
  };
  Eigen::Quaterniond truth = Eigen::Quaterniond::Identity();  // sensor, from t = 0
  std::vector<Eigen::Quaterniond> truth_at;                   // per sample
  truth_at.push_back(truth);
  gyro.add(0, Eigen::Vector3d::Zero());
  for (int k = 1; k <= 200 * 30; ++k) {
    const double t = k / 200.0;
    const Eigen::Vector3d w = true_rate(t - 0.0025);  // mean over the interval (midpoint)
    truth = truth * expRotation(kSensorFromImu * w / 200.0);
    truth_at.push_back(truth);
    Eigen::Vector3d n(normal(rng), normal(rng), normal(rng));
    gyro.add(5000LL * k, w + bias + noise * n);
  }
  const double initial_error = (gyro.bias() - bias).norm();
  std::normal_distribution<double> jitter(0.0, 0.003);
  const auto noisy = [&](int k) {
    return truth_at[static_cast<std::size_t>(k)] *
           expRotation(Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng)));
  };
  for (int k = 0; k + 100 <= 200 * 30; k += 100) {  // 0.5 s windows
    ASSERT_TRUE(
        gyro.updateBias(5000LL * k, 5000LL * (k + 100), noisy(k).conjugate() * noisy(k + 100)));
  }
  const double final_error = (gyro.bias() - bias).norm();
  EXPECT_GT(initial_error, 0.02);
  EXPECT_LT(final_error, 0.004) << gyro.bias().transpose();
  EXPECT_LT(gyro.biasStd().maxCoeff(), 0.004);
  // Corrected over 10 s: the bias alone turns it by 0.28 rad, the white noise by 0.027 rad
  // (RMS of 0.005 rad/sqrt(s) sqrt(10 s) on three axes).
  const Eigen::Quaterniond true_delta = truth_at[2000].conjugate() * truth_at[4000];
  const auto delta = gyro.deltaRotation(5000LL * 2000, 5000LL * 4000);
  const auto raw = gyro.rawDeltaRotationImu(5000LL * 2000, 5000LL * 4000);
  ASSERT_TRUE(delta.has_value() && raw.has_value());
  EXPECT_LT(delta->angularDistance(true_delta), 0.07);
  EXPECT_GT((kSensorFromImu * *raw * kSensorFromImu.conjugate()).angularDistance(true_delta), 0.2);
  EXPECT_FALSE(gyro.updateBias(5000LL * 100, 5000LL * 100, Eigen::Quaterniond::Identity()));
}

TEST(GyroPrior, BiasUncertaintyGrowsWithItsRandomWalk) {
  GyroPriorConfig config;
  config.initial_bias_std = 0.0;
  config.bias_random_walk = 0.01;
  GyroPrior gyro(config);
  for (int k = 0; k <= 100; ++k) gyro.add(100000LL * k, Eigen::Vector3d::Zero());  // 10 s
  EXPECT_NEAR(gyro.biasStd().x(), 0.01 * std::sqrt(10.0), 1e-9);
  EXPECT_NEAR(gyro.rotationVariance(0.5, 10000000),
              config.noise_density * config.noise_density * 0.5 + 0.001 * 0.25, 1e-12);
  // The variance at a time does not depend on samples beyond it.
  gyro.add(20000000, Eigen::Vector3d::Zero());
  EXPECT_NEAR(gyro.rotationVariance(0.5, 10000000),
              config.noise_density * config.noise_density * 0.5 + 0.001 * 0.25, 1e-12);
}

TEST(FitRotation, RecoversRotationAndOffset) {
  const Eigen::Quaterniond r(Eigen::AngleAxisd(2.0, Eigen::Vector3d(0.3, 0.9, -0.4).normalized()));
  const Eigen::Vector3d c(0.05, -0.02, 0.01);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Eigen::Vector3d> from, to;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d v(normal(rng), normal(rng), normal(rng));
    const Eigen::Vector3d n(normal(rng), normal(rng), normal(rng));
    from.push_back(v);
    to.push_back(r * v + c + 0.01 * n);
  }
  Eigen::Vector3d offset;
  double rms = 0.0;
  const Eigen::Quaterniond fit = fitRotation(from, to, &offset, &rms);
  EXPECT_LT(fit.angularDistance(r), 0.005);
  EXPECT_LT((offset - c).norm(), 0.005);
  EXPECT_NEAR(rms, 0.01 * std::sqrt(3.0), 0.004);
  // Without the offset the fit is biased by it and its residual larger.
  double rms_without = 0.0;
  fitRotation(from, to, nullptr, &rms_without);
  EXPECT_GT(rms_without, rms + 0.02);
  // One axis only: unobservable.
  std::vector<Eigen::Vector3d> line_from, line_to;
  for (int i = 1; i <= 10; ++i) {
    line_from.push_back(Eigen::Vector3d(i, 0.0, 0.0));
    line_to.push_back(r * line_from.back());
  }
  EXPECT_THROW(fitRotation(line_from, line_to), std::invalid_argument);
  EXPECT_THROW(fitRotation({from[0], from[1]}, {to[0], to[1]}), std::invalid_argument);
  EXPECT_THROW(fitRotation(from, {to[0], to[1], to[2]}), std::invalid_argument);
}

// Calibration on simulated readings with a known mounting: the shaking hand-held motion turns
// about every axis. The sensor path is the truth with 2 mrad jitter (a filter's estimate).
TEST(CalibrateSensorFromImu, RecoversAKnownMountingFromSimulatedReadings) {
  const Trajectory path = makeHandheldMotion(HandheldMotion::kShake, 20.0, 1);
  ImuSimulatorConfig imu;
  imu.body_from_imu =
      Eigen::Quaterniond(Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.2, -0.5, 0.8).normalized()));
  imu.seed = 5;
  const std::vector<ImuReading> readings = simulateImu(path, 0.0, 20.0, imu);
  std::vector<GyroSample> samples;
  for (const ImuReading& r : readings) {
    samples.push_back({std::llround(r.t_s * 1e6), r.gyro});
  }
  Trajectory estimate = path;
  std::mt19937_64 rng(9);
  std::normal_distribution<double> jitter(0.0, 0.002);
  for (StampedPose& p : estimate) {
    p.orientation =
        p.orientation * expRotation(Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng)));
  }
  const auto calibration = calibrateSensorFromImu(samples, estimate);
  ASSERT_TRUE(calibration.has_value());
  EXPECT_LT(calibration->sensor_from_imu.angularDistance(imu.body_from_imu) * 180.0 / M_PI, 1.0);
  EXPECT_GT(calibration->pairs, 50u);
  EXPECT_LT(calibration->rms_residual, 0.1);  // rad/s
  EXPECT_LT((calibration->bias - readings[readings.size() / 2].gyro_bias).norm(), 0.03);
  // A wrong mounting leaves a large residual: the fit's residual flags a bad pairing.
  std::vector<GyroSample> shuffled = samples;
  for (std::size_t i = 0; i < shuffled.size(); ++i) {
    shuffled[i].rate = samples[(i * 7919) % samples.size()].rate;
  }
  const auto bad = calibrateSensorFromImu(shuffled, estimate);
  if (bad) {
    EXPECT_GT(bad->rms_residual, 3.0 * calibration->rms_residual);
  }
  // A path that does not turn: nothing.
  Trajectory still = path;
  for (StampedPose& p : still) p.orientation = Eigen::Quaterniond::Identity();
  EXPECT_FALSE(calibrateSensorFromImu(samples, still).has_value());
}

}  // namespace
}  // namespace ebslam

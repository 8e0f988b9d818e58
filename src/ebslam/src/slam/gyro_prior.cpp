#include "ebslam/slam/gyro_prior.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/SVD>

namespace ebslam {

namespace {

// exp of a rotation vector [rad] as a unit quaternion (exact; series near zero).
Eigen::Quaterniond expRotation(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  if (angle < 1e-9)
    return Eigen::Quaterniond(1.0, 0.5 * v.x(), 0.5 * v.y(), 0.5 * v.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, v / angle));
}

// log of a unit quaternion: rotation vector [rad], angle in [0, pi].
Eigen::Vector3d logRotation(Eigen::Quaterniond q) {
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const double s = q.vec().norm();
  if (s < 1e-12) return 2.0 * q.vec();
  return 2.0 * std::atan2(s, q.w()) / s * q.vec();
}

}  // namespace

void GyroPriorConfig::validate() const {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("GyroPriorConfig: " + what);
  };
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  const double n = sensor_from_imu.norm();
  if (!(std::abs(n - 1.0) < 1e-3)) fail("sensor_from_imu must be a unit quaternion");
  if (!(noise_density >= 0.0) || !std::isfinite(noise_density)) {
    fail("noise_density must be finite and >= 0");
  }
  if (!(bias_random_walk >= 0.0) || !std::isfinite(bias_random_walk)) {
    fail("bias_random_walk must be finite and >= 0");
  }
  if (!(initial_bias_std >= 0.0) || !std::isfinite(initial_bias_std)) {
    fail("initial_bias_std must be finite and >= 0");
  }
  if (!positive(measurement_std_rad)) fail("measurement_std_rad must be positive");
  if (!positive(max_sample_gap_s)) fail("max_sample_gap_s must be positive");
  if (!(max_extrapolation_s >= 0.0) || !std::isfinite(max_extrapolation_s)) {
    fail("max_extrapolation_s must be finite and >= 0");
  }
  if (!positive(max_rate)) fail("max_rate must be positive");
}

GyroPrior::GyroPrior(const GyroPriorConfig& config) {
  setConfig(config);
  const double v = config_.initial_bias_std * config_.initial_bias_std;
  bias_cov_ = v * Eigen::Matrix3d::Identity();
}

void GyroPrior::setConfig(const GyroPriorConfig& config) {
  config.validate();
  config_ = config;
  sensor_from_imu_ = config.sensor_from_imu.normalized();
}

GyroPrior::AddResult GyroPrior::add(const GyroSample& sample) {
  if (!sample.rate.allFinite()) return AddResult::kNonFinite;
  if (sample.rate.cwiseAbs().maxCoeff() > config_.max_rate) return AddResult::kSaturated;
  if (!samples_.empty() && sample.t_us <= samples_.back().t_us) return AddResult::kOutOfOrder;
  if (!bias_cov_time_set_) {
    bias_cov_time_set_ = true;
    bias_cov_time_us_ = sample.t_us;
  }
  samples_.push_back(sample);
  return AddResult::kAccepted;
}

Eigen::Matrix3d GyroPrior::biasCovarianceAt(std::int64_t t_us) const {
  Eigen::Matrix3d c = bias_cov_;
  if (bias_cov_time_set_ && t_us > bias_cov_time_us_) {
    const double dt = 1e-6 * static_cast<double>(t_us - bias_cov_time_us_);
    c.diagonal().array() += config_.bias_random_walk * config_.bias_random_walk * dt;
  }
  return c;
}

std::int64_t GyroPrior::lastSampleTime() const {
  return samples_.empty() ? std::numeric_limits<std::int64_t>::min() : samples_.back().t_us;
}

std::optional<Eigen::Quaterniond> GyroPrior::integrate(std::int64_t t0_us, std::int64_t t1_us,
                                                       const Eigen::Vector3d& bias,
                                                       Eigen::Matrix3d* bias_jacobian) const {
  if (t1_us < t0_us) {
    throw std::invalid_argument("GyroPrior: interval ends (" + std::to_string(t1_us) +
                                " us) before it starts (" + std::to_string(t0_us) + " us)");
  }
  if (samples_.empty() || t0_us < samples_.front().t_us) return std::nullopt;
  const std::int64_t last = samples_.back().t_us;
  if (static_cast<double>(t1_us - last) > 1e6 * config_.max_extrapolation_s) return std::nullopt;
  const auto max_gap_us = static_cast<std::int64_t>(1e6 * config_.max_sample_gap_s);
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  if (bias_jacobian) bias_jacobian->setZero();
  // A: d log(q) / d bias, for the rotation from t0 to the current time. Stepping by D = exp(w dt)
  // maps A to D^T A - dt I (the bias enters with a minus sign; right Jacobian ~ I over one step).
  const auto step = [&](const Eigen::Vector3d& rate, double dt) {
    const Eigen::Quaterniond d = expRotation((rate - bias) * dt);
    q = q * d;
    if (bias_jacobian) {
      *bias_jacobian = d.conjugate().toRotationMatrix() * *bias_jacobian;
      bias_jacobian->diagonal().array() -= dt;
    }
  };
  // First sample ending after t0.
  auto it = std::upper_bound(samples_.begin(), samples_.end(), t0_us,
                             [](std::int64_t t, const GyroSample& s) { return t < s.t_us; });
  std::int64_t t = t0_us;
  for (; it != samples_.end() && t < t1_us; ++it) {
    const std::int64_t start = std::prev(it)->t_us;  // it > begin: front().t_us <= t0
    if (it->t_us - start > max_gap_us) return std::nullopt;
    const std::int64_t end = std::min(it->t_us, t1_us);
    if (end > t) step(it->rate, 1e-6 * static_cast<double>(end - t));
    t = end;
  }
  if (t < t1_us) step(samples_.back().rate, 1e-6 * static_cast<double>(t1_us - t));  // hold
  return q.normalized();
}

std::optional<Eigen::Quaterniond> GyroPrior::rawDeltaRotationImu(std::int64_t t0_us,
                                                                 std::int64_t t1_us) const {
  return integrate(t0_us, t1_us, Eigen::Vector3d::Zero(), nullptr);
}

std::optional<Eigen::Quaterniond> GyroPrior::deltaRotation(std::int64_t t0_us,
                                                           std::int64_t t1_us) const {
  const std::optional<Eigen::Quaterniond> imu = integrate(t0_us, t1_us, bias_, nullptr);
  if (!imu) return std::nullopt;
  return (sensor_from_imu_ * *imu * sensor_from_imu_.conjugate()).normalized();
}

double GyroPrior::rotationVariance(double dt_s, std::int64_t at_us) const {
  return config_.noise_density * config_.noise_density * dt_s +
         biasCovarianceAt(at_us).diagonal().maxCoeff() * dt_s * dt_s;
}

Eigen::Vector3d GyroPrior::biasStd() const {
  return biasCovarianceAt(lastSampleTime()).diagonal().cwiseSqrt();
}

void GyroPrior::setBias(const Eigen::Vector3d& bias_imu, double std_rad_s) {
  if (!bias_imu.allFinite() || !(std_rad_s >= 0.0) || !std::isfinite(std_rad_s)) {
    throw std::invalid_argument("GyroPrior::setBias: bias and std must be finite, std >= 0");
  }
  bias_ = bias_imu;
  bias_cov_ = std_rad_s * std_rad_s * Eigen::Matrix3d::Identity();
  bias_cov_time_set_ = !samples_.empty();
  bias_cov_time_us_ = samples_.empty() ? 0 : samples_.back().t_us;
}

bool GyroPrior::updateBias(std::int64_t t0_us, std::int64_t t1_us,
                           const Eigen::Quaterniond& estimated) {
  if (t1_us - t0_us < 1000) return false;
  Eigen::Matrix3d jacobian;
  const std::optional<Eigen::Quaterniond> imu = integrate(t0_us, t1_us, bias_, &jacobian);
  if (!imu) return false;
  // Residual in the IMU frame: gyro(bias_) = gyro(bias_true) exp(jacobian (bias_ - bias_true)),
  // so log(estimated^-1 gyro(bias_)) = -jacobian (bias_true - bias_) + noise.
  const Eigen::Quaterniond estimated_imu =
      sensor_from_imu_.conjugate() * estimated.normalized() * sensor_from_imu_;
  const Eigen::Vector3d residual = logRotation(estimated_imu.conjugate() * *imu);
  const double dt = 1e-6 * static_cast<double>(t1_us - t0_us);
  const Eigen::Matrix3d h = -jacobian;  // residual = h (bias_true - bias_) + noise
  const Eigen::Matrix3d prior = biasCovarianceAt(t1_us);
  const double r = config_.measurement_std_rad * config_.measurement_std_rad +
                   config_.noise_density * config_.noise_density * dt;
  const Eigen::Matrix3d s = h * prior * h.transpose() + r * Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d gain = prior * h.transpose() * s.inverse();
  bias_ += gain * residual;
  const Eigen::Matrix3d posterior = (Eigen::Matrix3d::Identity() - gain * h) * prior;
  bias_cov_ = 0.5 * (posterior + posterior.transpose());
  bias_cov_time_us_ = std::max(bias_cov_time_us_, t1_us);
  return true;
}

void GyroPrior::discardBefore(std::int64_t t_us) {
  // Keep the last sample at or before t_us: it starts the interval that covers t_us.
  while (samples_.size() >= 2 && samples_[1].t_us <= t_us) samples_.pop_front();
}

void GyroPrior::clearSamples() { samples_.clear(); }

Eigen::Quaterniond fitRotation(const std::vector<Eigen::Vector3d>& from,
                               const std::vector<Eigen::Vector3d>& to, Eigen::Vector3d* offset,
                               double* rms_residual) {
  if (from.size() != to.size()) throw std::invalid_argument("fitRotation: size mismatch");
  if (from.size() < 3) throw std::invalid_argument("fitRotation: need at least 3 pairs");
  Eigen::Vector3d mean_from = Eigen::Vector3d::Zero(), mean_to = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < from.size(); ++i) {
    if (!from[i].allFinite() || !to[i].allFinite()) {
      throw std::invalid_argument("fitRotation: non-finite vector at " + std::to_string(i));
    }
    mean_from += from[i];
    mean_to += to[i];
  }
  const double n = static_cast<double>(from.size());
  mean_from /= n;
  mean_to /= n;
  if (!offset) {
    mean_from.setZero();
    mean_to.setZero();
  }
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < from.size(); ++i) {
    cross += (to[i] - mean_to) * (from[i] - mean_from).transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d sv = svd.singularValues();
  if (!(sv[0] > 0.0) || sv[1] < 1e-3 * sv[0]) {
    throw std::invalid_argument(
        "fitRotation: the vectors do not span two directions (rotation unobservable)");
  }
  Eigen::Matrix3d correction = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) correction(2, 2) = -1.0;
  const Eigen::Matrix3d rotation = svd.matrixU() * correction * svd.matrixV().transpose();
  const Eigen::Vector3d c = mean_to - rotation * mean_from;
  if (offset) *offset = c;
  if (rms_residual) {
    double sum = 0.0;
    for (std::size_t i = 0; i < from.size(); ++i) {
      sum += (to[i] - rotation * from[i] - c).squaredNorm();
    }
    *rms_residual = std::sqrt(sum / n);
  }
  return Eigen::Quaterniond(rotation).normalized();
}

std::optional<GyroCalibration> calibrateSensorFromImu(const std::vector<GyroSample>& samples,
                                                      const Trajectory& sensor_poses,
                                                      const GyroCalibrationConfig& config) {
  if (!(config.window_s > 0.0) || !std::isfinite(config.window_s) || !(config.min_rate >= 0.0) ||
      config.min_pairs < 3) {
    throw std::invalid_argument(
        "calibrateSensorFromImu: need window_s > 0, min_rate >= 0, min_pairs >= 3");
  }
  if (samples.size() < 2 || sensor_poses.size() < 2) return std::nullopt;
  // Windows over the span both cover; the gyro's mean rate over a window is its samples'
  // duration-weighted mean (sample k covers (t_{k-1}, t_k]).
  const double t_begin =
      std::max(sensor_poses.front().t_s, 1e-6 * static_cast<double>(samples.front().t_us));
  const double t_end =
      std::min(sensor_poses.back().t_s, 1e-6 * static_cast<double>(samples.back().t_us));
  std::vector<Eigen::Vector3d> gyro, sensor;
  std::size_t k = 1;
  for (double t0 = t_begin; t0 + config.window_s <= t_end; t0 += config.window_s) {
    const double t1 = t0 + config.window_s;
    const Eigen::Quaterniond r0 = interpolatePose(sensor_poses, t0).orientation;
    const Eigen::Quaterniond r1 = interpolatePose(sensor_poses, t1).orientation;
    const Eigen::Vector3d w_sensor = logRotation(r0.conjugate() * r1) / config.window_s;
    if (w_sensor.norm() < config.min_rate) continue;
    const auto a_us = static_cast<std::int64_t>(std::llround(t0 * 1e6));
    const auto b_us = static_cast<std::int64_t>(std::llround(t1 * 1e6));
    while (k < samples.size() && samples[k].t_us <= a_us) ++k;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::int64_t covered = 0;
    for (std::size_t j = k; j < samples.size() && samples[j - 1].t_us < b_us; ++j) {
      const std::int64_t lo = std::max(samples[j - 1].t_us, a_us);
      const std::int64_t hi = std::min(samples[j].t_us, b_us);
      if (hi > lo) {
        sum += samples[j].rate * static_cast<double>(hi - lo);
        covered += hi - lo;
      }
    }
    if (covered < (b_us - a_us) * 9 / 10) continue;  // a gap in the samples
    gyro.push_back(sum / static_cast<double>(covered));
    sensor.push_back(w_sensor);
  }
  if (gyro.size() < config.min_pairs) return std::nullopt;
  GyroCalibration result;
  Eigen::Vector3d offset;
  try {
    result.sensor_from_imu = fitRotation(gyro, sensor, &offset, &result.rms_residual);
  } catch (const std::invalid_argument&) {
    return std::nullopt;  // one axis only
  }
  result.bias = -(result.sensor_from_imu.conjugate() * offset);
  result.pairs = gyro.size();
  return result;
}

}  // namespace ebslam

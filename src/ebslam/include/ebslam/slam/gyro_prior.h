#pragma once

// Gyro integrator for EB-SLAM-3D's rotation prior: integrates timestamped angular rates (IMU
// frame, [rad/s]) into the rotation of the event sensor between two event times, minus an online
// bias estimate, and says how uncertain that rotation is. Frames: rates are measured in the IMU
// frame; sensor_from_imu rotates IMU vectors into the event sensor's optical frame (x right,
// y down, z forward). A rotation "between t0 and t1" is R(t0)^T R(t1), R the sensor -> map
// rotation, i.e. an increment in the sensor frame (right-multiplied). Time: microseconds on the
// event clock. Sample convention: a sample stamped t_k holds the mean rate over (t_{k-1}, t_k]
// (what a gyro with an averaging output filter reports; the simulator's readings are exactly
// this), so the integral over whole sample intervals is exact for noise-free readings.
// Bias: one Kalman filter per axis (IMU frame) with a random-walk model; its measurements are the
// difference between the gyro's bias-corrected rotation and an independent rotation estimate
// (EB-SLAM-3D's own estimate) over a window. Details: docs/ebslam_core.md#eb-slam-3d-imu

#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ebslam/events/trajectory.h"

namespace ebslam {

/// One gyro reading: mean angular rate over the interval ending at t_us, IMU frame [rad/s].
struct GyroSample {
  std::int64_t t_us = 0;
  Eigen::Vector3d rate = Eigen::Vector3d::Zero();
};

struct GyroPriorConfig {
  /// IMU frame -> event sensor frame (unit quaternion): rate_sensor = sensor_from_imu * rate_imu.
  Eigen::Quaterniond sensor_from_imu = Eigen::Quaterniond::Identity();
  /// White rate noise density [rad/s/sqrt(Hz)] = angle random walk [rad/sqrt(s)] (consumer MEMS:
  /// 0.005).
  double noise_density = 0.005;
  /// Bias random walk [rad/s per sqrt(s)]: the bias' std. dev. grows by this times sqrt(t).
  double bias_random_walk = 0.01;
  /// Prior std. dev. of each bias axis before any measurement [rad/s] (turn-on bias).
  double initial_bias_std = 0.02;
  /// Std. dev. of each axis of a rotation-estimate difference used as a bias measurement [rad]
  /// (the independent estimate's jitter at the window's two ends, combined).
  double measurement_std_rad = 0.01;
  /// A gap between two samples longer than this [s] leaves the interval without a rate: rotations
  /// across it are not predicted (deltaRotation returns nothing).
  double max_sample_gap_s = 0.05;
  /// Beyond the last sample the last rate is held for at most this long [s].
  double max_extrapolation_s = 0.02;
  /// Samples with a component above this magnitude [rad/s] are rejected (saturated or corrupt).
  double max_rate = 35.0;

  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

class GyroPrior {
 public:
  /// Throws std::invalid_argument for an invalid config.
  explicit GyroPrior(const GyroPriorConfig& config = {});

  enum class AddResult {
    kAccepted,
    kNonFinite,   ///< a rate is NaN or infinite (dropped)
    kSaturated,   ///< a component above max_rate (dropped)
    kOutOfOrder,  ///< not later than the last accepted sample (dropped)
  };
  /// Adds a reading; rejected readings change nothing.
  AddResult add(const GyroSample& sample);
  AddResult add(std::int64_t t_us, const Eigen::Vector3d& rate_imu) {
    return add({t_us, rate_imu});
  }

  /// Bias-corrected rotation of the sensor frame from t0_us to t1_us (sensor frame increment,
  /// see above); nothing when the samples do not cover [t0, t1] (before the first sample, a
  /// gap longer than max_sample_gap_s, or more than max_extrapolation_s beyond the last).
  /// t1 < t0 throws std::invalid_argument.
  std::optional<Eigen::Quaterniond> deltaRotation(std::int64_t t0_us, std::int64_t t1_us) const;
  /// As deltaRotation without the bias correction, in the IMU frame.
  std::optional<Eigen::Quaterniond> rawDeltaRotationImu(std::int64_t t0_us,
                                                        std::int64_t t1_us) const;
  /// Variance of each axis of deltaRotation's error over dt_s [rad^2] for an interval ending at
  /// at_us: white noise noise_density^2 dt plus the bias uncertainty at at_us (per axis,
  /// largest) times dt^2.
  double rotationVariance(double dt_s, std::int64_t at_us) const;

  /// Bias measurement: `estimated` is an independent estimate of the sensor's rotation from
  /// t0_us to t1_us (same convention as deltaRotation). Updates the bias estimate with the
  /// difference. Returns false (nothing changed) when the samples do not cover the window or
  /// it is shorter than 1 ms.
  bool updateBias(std::int64_t t0_us, std::int64_t t1_us, const Eigen::Quaterniond& estimated);

  /// Current bias estimate, IMU frame [rad/s], and its std. dev. per axis [rad/s] (grown by the
  /// random walk from the last measurement up to the last sample's time).
  const Eigen::Vector3d& bias() const { return bias_; }
  Eigen::Vector3d biasStd() const;
  void setBias(const Eigen::Vector3d& bias_imu, double std_rad_s);

  /// Drops samples no longer needed for times >= t_us (keeps the one ending at or before it).
  void discardBefore(std::int64_t t_us);
  /// Drops every sample (the bias estimate is kept: it belongs to the sensor).
  void clearSamples();

  bool empty() const { return samples_.empty(); }
  std::size_t sampleCount() const { return samples_.size(); }
  /// Time of the last accepted sample [us] (INT64_MIN before the first).
  std::int64_t lastSampleTime() const;
  const GyroPriorConfig& config() const { return config_; }
  /// Changes the config (e.g. a new sensor_from_imu); samples and bias are kept. Throws
  /// std::invalid_argument for an invalid config.
  void setConfig(const GyroPriorConfig& config);

 private:
  // Bias covariance grown by the random walk from its reference time to t_us.
  Eigen::Matrix3d biasCovarianceAt(std::int64_t t_us) const;
  // Integrates the rates minus `bias` (IMU frame) over [t0, t1]; optionally the sensitivity of
  // the result's rotation vector to a bias error (d log / d bias, IMU frame).
  std::optional<Eigen::Quaterniond> integrate(std::int64_t t0_us, std::int64_t t1_us,
                                              const Eigen::Vector3d& bias,
                                              Eigen::Matrix3d* bias_jacobian) const;

  GyroPriorConfig config_;
  Eigen::Quaterniond sensor_from_imu_;  // normalised
  std::deque<GyroSample> samples_;
  Eigen::Vector3d bias_ = Eigen::Vector3d::Zero();  // IMU frame [rad/s]
  // Bias covariance [rad^2/s^2] at bias_cov_time_us_ (the last bias measurement, else the first
  // sample); it grows from there with the random walk at the time of a query, so that results
  // do not depend on how far ahead of the events the samples arrived.
  Eigen::Matrix3d bias_cov_;
  std::int64_t bias_cov_time_us_ = 0;
  bool bias_cov_time_set_ = false;
};

/// Rotation R (unit quaternion) that best maps `from` vectors onto `to` vectors (Kabsch /
/// orthogonal Procrustes, weights 1): to_i ~ R from_i, or with `offset` given to_i ~ R from_i + c
/// (centroids removed first; *offset receives c). Used to calibrate sensor_from_imu: from = gyro
/// rates (IMU frame), to = the sensor's angular velocities from a pose estimate at the same times;
/// with the offset the gyro bias drops out (c = -R bias). `rms_residual` (optional) receives the
/// RMS of |to_i - R from_i (- c)| [units of the vectors]. Throws std::invalid_argument for fewer
/// than 3 pairs, a size mismatch, non-finite values, or vectors that do not span two directions
/// (second singular value below 1e-3 of the first: the rotation about that axis is unobservable).
Eigen::Quaterniond fitRotation(const std::vector<Eigen::Vector3d>& from,
                               const std::vector<Eigen::Vector3d>& to,
                               Eigen::Vector3d* offset = nullptr, double* rms_residual = nullptr);

/// Calibration of sensor_from_imu from one recording: pairs of the gyro's mean rate and the
/// sensor's angular velocity from a pose trajectory (e.g. EB-SLAM-3D's estimate, sensor -> map)
/// over windows of window_s, keeping windows where the trajectory turns faster than min_rate.
struct GyroCalibrationConfig {
  double window_s = 0.1;  ///< [s] length of one pair's window (windows do not overlap)
  double min_rate = 0.3;  ///< [rad/s] windows turning slower say little about the axes
  std::size_t min_pairs = 20;
};
struct GyroCalibration {
  Eigen::Quaterniond sensor_from_imu = Eigen::Quaterniond::Identity();
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();  ///< gyro bias, IMU frame [rad/s]
  double rms_residual = 0.0;                       ///< [rad/s] of the pairs after the fit
  std::size_t pairs = 0;
};
/// Fits sensor_from_imu and the bias (fitRotation with offset). Nothing if fewer than min_pairs
/// windows turn fast enough or they span one axis only. Samples in time order (GyroPrior
/// convention); throws std::invalid_argument for an invalid config.
std::optional<GyroCalibration> calibrateSensorFromImu(const std::vector<GyroSample>& samples,
                                                      const Trajectory& sensor_poses,
                                                      const GyroCalibrationConfig& config = {});

}  // namespace ebslam

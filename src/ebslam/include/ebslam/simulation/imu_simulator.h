#pragma once

// IMU readings from a ground-truth body trajectory (a consumer MEMS IMU rigidly mounted on the
// body): gyro = the mean angular rate over the interval since the previous reading (GyroPrior's
// convention, gyro_prior.h) + a random-walk bias + white noise; accelerometer = specific force
// (acceleration minus gravity) from the second difference of the interpolated path, + a constant
// bias + white noise. Both in the IMU frame; body_from_imu rotates IMU vectors into the body frame
// (the IMU's origin is the body's: lever-arm effects are not modelled). Time: the trajectory
// clock [s], readings at t_begin + k / rate_hz. Deterministic per seed. Units: noise densities per
// sqrt(Hz), bias random walk per sqrt(s). Details: docs/ebslam_core.md#eb-slam-3d-imu

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ebslam/events/trajectory.h"

namespace ebslam {

struct ImuSimulatorConfig {
  double rate_hz = 200.0;  ///< readings per second
  /// Gyro white noise density [rad/s/sqrt(Hz)]: per-reading std. dev. = density sqrt(rate_hz).
  double gyro_noise_density = 0.005;
  /// Gyro bias random walk [rad/s per sqrt(s)]: the bias' std. dev. grows by this times sqrt(t).
  double gyro_bias_random_walk = 0.01;
  double gyro_initial_bias_std = 0.01;  ///< turn-on bias, std. dev. per axis [rad/s]
  /// Accelerometer white noise density [m/s^2/sqrt(Hz)] and constant bias std. dev. per axis
  /// [m/s^2] (consumer MEMS: ~150 ug/sqrt(Hz), ~50 mg turn-on).
  double accel_noise_density = 0.0015;
  double accel_bias_std = 0.05;
  /// IMU frame -> body frame. Default: an IMU with REP 103 body axes (x forward, y left, z up)
  /// on a body with optical axes (x right, y down, z forward), as on most RGB-D cameras.
  Eigen::Quaterniond body_from_imu = defaultBodyFromImu();
  Eigen::Vector3d gravity_world{0.0, 0.0, -9.81};  ///< [m/s^2] in the trajectory's world frame
  std::uint64_t seed = 1;

  static Eigen::Quaterniond defaultBodyFromImu();
  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

/// One simulated reading with its truth.
struct ImuReading {
  double t_s = 0.0;                                     ///< trajectory clock [s]
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();       ///< [rad/s], IMU frame
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();      ///< specific force [m/s^2], IMU frame
  Eigen::Vector3d true_rate = Eigen::Vector3d::Zero();  ///< noise- and bias-free gyro [rad/s]
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();  ///< bias in this reading [rad/s]
};

/// Readings of an IMU on `body` (body -> world) from t_begin_s to t_end_s (both within the
/// trajectory). Throws std::invalid_argument for an invalid config, trajectory or time range.
std::vector<ImuReading> simulateImu(const Trajectory& body, double t_begin_s, double t_end_s,
                                    const ImuSimulatorConfig& config);

}  // namespace ebslam

#include "ebslam/simulation/imu_simulator.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace ebslam {

namespace {

Eigen::Vector3d logRotation(Eigen::Quaterniond q) {
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const double s = q.vec().norm();
  if (s < 1e-12) return 2.0 * q.vec();
  return 2.0 * std::atan2(s, q.w()) / s * q.vec();
}

}  // namespace

Eigen::Quaterniond ImuSimulatorConfig::defaultBodyFromImu() {
  // Columns: the IMU's x (forward) = optical z, y (left) = optical -x, z (up) = optical -y.
  Eigen::Matrix3d r;
  r << 0.0, -1.0, 0.0,  //
      0.0, 0.0, -1.0,   //
      1.0, 0.0, 0.0;
  return Eigen::Quaterniond(r);
}

void ImuSimulatorConfig::validate() const {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("ImuSimulatorConfig: " + what);
  };
  const auto non_negative = [](double v) { return v >= 0.0 && std::isfinite(v); };
  if (!(rate_hz > 0.0 && rate_hz <= 100000.0)) fail("rate_hz must be in (0, 100000]");
  if (!non_negative(gyro_noise_density) || !non_negative(gyro_bias_random_walk) ||
      !non_negative(gyro_initial_bias_std) || !non_negative(accel_noise_density) ||
      !non_negative(accel_bias_std)) {
    fail("noise densities, random walk and bias std. devs. must be finite and >= 0");
  }
  if (!(std::abs(body_from_imu.norm() - 1.0) < 1e-3))
    fail("body_from_imu must be a unit quaternion");
  if (!gravity_world.allFinite()) fail("gravity_world must be finite");
}

std::vector<ImuReading> simulateImu(const Trajectory& body, double t_begin_s, double t_end_s,
                                    const ImuSimulatorConfig& config) {
  config.validate();
  validateTrajectory(body, "simulateImu: body trajectory");
  if (body.size() < 2) throw std::invalid_argument("simulateImu: need at least two poses");
  if (!(t_begin_s >= body.front().t_s && t_end_s <= body.back().t_s && t_begin_s <= t_end_s)) {
    throw std::invalid_argument("simulateImu: [t_begin, t_end] must lie within the trajectory");
  }
  const double dt = 1.0 / config.rate_hz;
  const Eigen::Quaterniond body_from_imu = config.body_from_imu.normalized();
  const Eigen::Quaterniond imu_from_body = body_from_imu.conjugate();
  std::mt19937_64 rng(config.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto draw = [&] {  // x, y, z in this order
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = normal(rng);
    return v;
  };
  Eigen::Vector3d gyro_bias = config.gyro_initial_bias_std * draw();
  const Eigen::Vector3d accel_bias = config.accel_bias_std * draw();
  const double gyro_sigma = config.gyro_noise_density * std::sqrt(config.rate_hz);
  const double accel_sigma = config.accel_noise_density * std::sqrt(config.rate_hz);
  const double bias_step = config.gyro_bias_random_walk * std::sqrt(dt);
  const auto clamp = [&](double t) {
    return std::min(body.back().t_s, std::max(body.front().t_s, t));
  };
  std::vector<ImuReading> readings;
  const auto count =
      static_cast<std::size_t>(std::floor((t_end_s - t_begin_s) * config.rate_hz + 1e-9)) + 1;
  readings.reserve(count);
  for (std::size_t k = 0; k < count; ++k) {
    ImuReading r;
    r.t_s = t_begin_s + static_cast<double>(k) * dt;
    // Mean rate over (t - dt, t] (the first reading: over its first interval instead).
    double a = clamp(r.t_s - dt), b = clamp(r.t_s);
    if (b - a < 0.5 * dt) {
      a = clamp(r.t_s);
      b = clamp(r.t_s + dt);
    }
    const StampedPose pa = interpolatePose(body, a), pb = interpolatePose(body, b);
    const Eigen::Vector3d rate_body =
        b > a ? Eigen::Vector3d(logRotation(pa.orientation.conjugate() * pb.orientation) / (b - a))
              : Eigen::Vector3d::Zero();
    r.true_rate = imu_from_body * rate_body;
    if (k > 0) gyro_bias += bias_step * draw();
    r.gyro_bias = gyro_bias;
    r.gyro = r.true_rate + gyro_bias + gyro_sigma * draw();
    // Specific force from the second difference of the interpolated path over +-dt.
    const double t_minus = clamp(r.t_s - dt), t_plus = clamp(r.t_s + dt), t_mid = clamp(r.t_s);
    Eigen::Vector3d accel_world = Eigen::Vector3d::Zero();
    if (t_plus > t_mid && t_mid > t_minus) {
      const Eigen::Vector3d v1 =
          (interpolatePose(body, t_plus).position - interpolatePose(body, t_mid).position) /
          (t_plus - t_mid);
      const Eigen::Vector3d v0 =
          (interpolatePose(body, t_mid).position - interpolatePose(body, t_minus).position) /
          (t_mid - t_minus);
      accel_world = (v1 - v0) / (0.5 * (t_plus - t_minus));
    }
    const Eigen::Quaterniond world_from_imu =
        interpolatePose(body, t_mid).orientation * body_from_imu;
    r.accel = world_from_imu.conjugate() * (accel_world - config.gravity_world) + accel_bias +
              accel_sigma * draw();
    readings.push_back(r);
  }
  return readings;
}

}  // namespace ebslam

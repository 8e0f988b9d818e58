#include "ebslam/simulation/handheld_motions.h"

#include <array>
#include <cmath>
#include <random>
#include <stdexcept>

#include <Eigen/Geometry>

namespace ebslam {
namespace {

// Optical frame looking along yaw (about world z, 0 = +x) and pitched down by `pitch` [rad]:
// columns x right, y down, z forward.
Eigen::Quaterniond lookingAt(double yaw, double pitch) {
  const Eigen::Vector3d z(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
                          -std::sin(pitch));
  const Eigen::Vector3d x(std::sin(yaw), -std::cos(yaw), 0.0);
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = y;
  r.col(2) = z;
  return Eigen::Quaterniond(r).normalized();
}

// Hand tremor: per axis, three sinusoids with frequencies in [f_lo, f_hi] Hz and random phases,
// normalised to an RMS of `rms` per axis.
class Tremor {
 public:
  Tremor(std::mt19937_64& rng, double f_lo, double f_hi, double rms) : rms_(rms) {
    std::uniform_real_distribution<double> f(f_lo, f_hi), phase(0.0, 2.0 * M_PI);
    for (auto& axis : terms_) {
      for (auto& term : axis) term = {2.0 * M_PI * f(rng), phase(rng)};
    }
  }
  Eigen::Vector3d at(double t) const {
    Eigen::Vector3d v;
    for (int a = 0; a < 3; ++a) {
      double sum = 0.0;
      for (const auto& term : terms_[a]) sum += std::sin(term[0] * t + term[1]);
      v[a] = rms_ * sum * std::sqrt(2.0 / 3.0);  // three unit sines: RMS sqrt(3/2)
    }
    return v;
  }

 private:
  std::array<std::array<std::array<double, 2>, 3>, 3> terms_{};
  double rms_;
};

// Smooth step 0 -> 1 over [t0, t0 + d] with zero velocity at both ends.
double smoothStep(double t, double t0, double d) {
  if (t <= t0) return 0.0;
  if (t >= t0 + d) return 1.0;
  return 0.5 * (1.0 - std::cos(M_PI * (t - t0) / d));
}

}  // namespace

const char* toString(HandheldMotion motion) {
  switch (motion) {
    case HandheldMotion::kYawTurn:
      return "yaw_turn";
    case HandheldMotion::kFloorSweep:
      return "floor_sweep";
    case HandheldMotion::kShake:
      return "shake";
    case HandheldMotion::kOrbit:
      return "orbit";
  }
  return "unknown";
}

HandheldMotion handheldMotionFromString(const std::string& name) {
  for (HandheldMotion m : {HandheldMotion::kYawTurn, HandheldMotion::kFloorSweep,
                           HandheldMotion::kShake, HandheldMotion::kOrbit}) {
    if (name == toString(m)) return m;
  }
  throw std::invalid_argument("unknown hand-held motion '" + name +
                              "' (yaw_turn, floor_sweep, shake, orbit)");
}

Trajectory makeHandheldMotion(HandheldMotion motion, double duration_s, std::uint64_t seed,
                              double rate_hz) {
  if (!(duration_s > 0.0) || !(rate_hz > 0.0) || !std::isfinite(duration_s * rate_hz)) {
    throw std::invalid_argument("makeHandheldMotion: duration and rate must be positive");
  }
  std::mt19937_64 rng(seed);
  const Tremor position_tremor(rng, 0.5, 3.0, 0.004);  // [m]
  const Tremor angle_tremor(rng, 0.5, 3.0, 0.006);     // [rad]
  const Tremor shake_position(rng, 2.5, 4.0, 0.02);    // [m], kShake only
  const Tremor shake_angle(rng, 2.5, 4.0, 0.05);       // [rad], kShake only
  Trajectory path;
  const auto count = static_cast<long>(std::floor(duration_s * rate_hz));
  for (long k = 0; k <= count; ++k) {
    const double t = static_cast<double>(k) / rate_hz;
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    double yaw = 0.0, pitch = 0.0;
    Eigen::Vector3d extra_angle = Eigen::Vector3d::Zero();
    switch (motion) {
      case HandheldMotion::kYawTurn: {
        position = Eigen::Vector3d(0.0, 0.0, 1.4) +
                   Eigen::Vector3d(0.05 * std::sin(0.4 * t), 0.04 * std::sin(0.3 * t + 1.0), 0.0);
        const double pan = 0.25 * std::sin(2.0 * M_PI * 0.15 * t);
        yaw = pan + 2.0 * M_PI * smoothStep(t, 5.0, 4.0);
        pitch = 10.0 * M_PI / 180.0 + 0.05 * std::sin(0.5 * t);
        break;
      }
      case HandheldMotion::kFloorSweep: {
        const double sweep = std::sin(2.0 * M_PI * 0.25 * t);
        position = Eigen::Vector3d(0.5 * sweep, 0.05 * t, 0.55 + 0.03 * std::sin(0.7 * t));
        yaw = M_PI / 2.0 + 0.17 * sweep;
        pitch = 60.0 * M_PI / 180.0;
        break;
      }
      case HandheldMotion::kShake: {
        position = Eigen::Vector3d(0.1 * std::sin(0.3 * t), 0.08 * std::sin(0.2 * t), 1.3) +
                   shake_position.at(t);
        yaw = 0.2 * std::sin(0.25 * t);
        pitch = 35.0 * M_PI / 180.0;
        extra_angle = shake_angle.at(t);
        break;
      }
      case HandheldMotion::kOrbit: {
        const Eigen::Vector3d target(0.0, 0.0, 0.85);
        const double azimuth = M_PI + 2.0 * M_PI * t / 12.0;
        const double radius = 0.45 + 0.2 * std::sin(2.0 * M_PI * t / 7.0);
        position =
            target + Eigen::Vector3d(radius * std::cos(azimuth), radius * std::sin(azimuth), 0.35);
        const Eigen::Vector3d view = target - position;
        yaw = std::atan2(view.y(), view.x());
        pitch = std::atan2(-view.z(), view.head<2>().norm());
        break;
      }
    }
    // Tremor and shake angles as a small rotation in the camera frame.
    const Eigen::Vector3d angle = angle_tremor.at(t) + extra_angle;
    StampedPose p;
    p.t_s = t;
    p.position = position + position_tremor.at(t);
    p.orientation =
        (lookingAt(yaw, pitch) *
         Eigen::Quaterniond(Eigen::AngleAxisd(
             angle.norm(), angle.norm() > 0.0 ? angle.normalized() : Eigen::Vector3d::UnitZ())))
            .normalized();
    path.push_back(p);
  }
  return path;
}

}  // namespace ebslam
